"""The interactive path: Blender with its UI (under a virtual X server), the Bake
button's INVOKE_DEFAULT run of omis.bake — modal, native work on a worker thread,
a responsive main loop, Esc cancelling with nothing written, then a bake that
completes and leaves its summary for the panel.

    scripts/blender_run.sh --ui tests/blender/test_modal_ui.py
"""

import os
import sys
import time
import traceback

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

from omis_bake import operators  # noqa: E402

MARK = (0.25, 0.5, 0.75, 0.5)
TIMEOUT = 120.0


def build_scene():
    U.reset_scene()
    img = U.make_image("ui", 64)
    U.set_pixels(img, MARK)
    ob = U.image_grid("Plane", img, size=1.0, cuts=1)
    U.add_light('AREA', "lamp", energy=200.0, location=(0.2, 0.1, 1.0), size=0.4)
    U.select_only([ob])
    return img


def ui_context():
    window = bpy.context.window_manager.windows[0]
    area = max(window.screen.areas, key=lambda a: a.width * a.height)
    region = next(r for r in area.regions if r.type == 'WINDOW')
    return window, area, region


def finish(code, message):
    print(message, flush=True)
    sys.stdout.flush()
    os._exit(code)


class Steps:
    def __init__(self, image):
        self.image = image
        self.start = time.perf_counter()
        self.state = "invoke_long"
        self.ticks = 0
        self.fractions = []

    def invoke(self, **settings):
        window, area, region = ui_context()
        with bpy.context.temp_override(window=window, area=area, region=region):
            result = bpy.ops.omis.bake('INVOKE_DEFAULT', **settings)
        U.check(result == {'RUNNING_MODAL'}, f"INVOKE_DEFAULT returned {result}")
        U.check(operators.running is not None, "no running job after invoke")
        return operators.running

    def __call__(self):
        try:
            if time.perf_counter() - self.start > TIMEOUT:
                finish(1, f"FAIL: timeout in state {self.state}")
            return self.step()
        except Exception:
            traceback.print_exc()
            finish(1, f"FAIL in state {self.state}")

    def step(self):
        if self.state == "invoke_long":
            self.job = self.invoke(samples=10 ** 6)
            self.state = "watch"
            return 0.05
        if self.state == "watch":
            # The main loop keeps running (this timer fires) while the worker bakes.
            self.ticks += 1
            self.fractions.append(self.job.fraction)
            U.check(not self.job.done, "the long bake ended before Esc")
            if self.ticks >= 5 and self.job.fraction > 0:
                window = bpy.context.window_manager.windows[0]
                window.event_simulate(type='ESC', value='PRESS')
                window.event_simulate(type='ESC', value='RELEASE')
                self.state = "cancelling"
            return 0.05
        if self.state == "cancelling":
            if operators.running is not None:
                return 0.05
            U.check(self.job.cancelled, "Esc did not cancel the job")
            px = U.pixels(self.image)
            U.check(np.allclose(px, np.asarray(MARK, np.float32)), "cancel changed the image")
            U.check(self.fractions == sorted(self.fractions), "progress went backwards")
            print(f"cancelled after {self.ticks} responsive ticks, fraction "
                  f"{self.fractions[-1]:.4f}", flush=True)
            self.job = self.invoke(samples=64)
            self.state = "complete"
            return 0.05
        if self.state == "complete":
            if operators.running is not None:
                return 0.05
            U.check(self.job.done and not self.job.cancelled and self.job.error is None,
                    f"second bake: cancelled={self.job.cancelled} error={self.job.error}")
            px = U.pixels(self.image)
            U.check(not np.allclose(px, np.asarray(MARK, np.float32)), "the bake wrote nothing")
            U.check(np.all(px[..., 3] == 1.0), "baked texels must be opaque")
            props = bpy.context.scene.omis
            U.check(props.last_status == "complete" and props.last_samples_per_texel == 64
                    and props.last_plan.startswith("effect plan"),
                    f"panel summary: {props.last_status} {props.last_samples_per_texel}")
            finish(0, "ok test_modal_ui")
        return None


image = build_scene()
bpy.app.timers.register(Steps(image), first_interval=0.5)
