"""Issue 12 items 5 and 6, with Blender's interface (virtual X server): the panel as
Blender draws it under Cycles and under EEVEE — one Render Properties panel of its
own under both, not inside Cycles' Bake panel —, screenshots of it, and a bake
started from it showing its progress and time left in the panel's header.

For each engine: Blender itself must call the panel's draw, the Bake operator must be
reachable from the Properties editor, and a screenshot with the panel must differ
clearly from one without it (the panel's region is not empty) — no pixel-exact
comparison. Screenshots go to <build>/test_screenshots/ for a person to look at.

    scripts/blender_run.sh --ui tests/blender/test_panel_screenshot.py
"""

import os
import sys
import time
import traceback

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

from omis_bake import operators, ui  # noqa: E402

TIMEOUT = 120.0
# OMIS_SCREENSHOT_DIR: where scripts/docs_images.sh collects docs/images/panel.png.
OUT = os.environ.get("OMIS_SCREENSHOT_DIR") or os.path.join(
    os.environ.get("OMIS_BUILD_DIR", U.temp_dir()), "test_screenshots")
# A panel of a dozen rows covers thousands of pixels of a ~1280×700 editor; 0.5 %
# of the area (~4500 px) is far above anti-aliasing jitter and far below a panel.
MIN_CHANGED = 0.005


def finish(code, message):
    print(message, flush=True)
    os._exit(code)


def build_scene():
    U.reset_scene()
    img = U.make_image("shot", 64)
    ob = U.image_grid("Plane", img, size=1.0, cuts=1)
    U.add_light('AREA', "lamp", energy=200.0, location=(0.2, 0.1, 1.0), size=0.4)
    U.select_only([ob])


def properties_area():
    """The largest area, turned into a Properties editor showing Render Properties."""
    window = bpy.context.window_manager.windows[0]
    area = max(window.screen.areas, key=lambda a: a.width * a.height)
    if area.type != 'PROPERTIES':
        area.type = 'PROPERTIES'
    space = area.spaces.active
    # The editor's tabs exist once it has been drawn: set the tab on a later call.
    try:
        if space.context != 'RENDER':
            space.context = 'RENDER'
    except TypeError:
        pass
    region = next(r for r in area.regions if r.type == 'WINDOW')
    return window, area, region


def screenshot(name):
    window, area, region = properties_area()
    path = os.path.join(OUT, name + ".png")
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.screen.screenshot_area(filepath=path)
    img = bpy.data.images.load(path, check_existing=False)
    px = np.empty(img.size[0] * img.size[1] * img.channels, np.float32)
    img.pixels.foreach_get(px)
    px = px.reshape(img.size[1], img.size[0], img.channels)[..., :3].copy()
    bpy.data.images.remove(img)
    print(f"screenshot {path} ({px.shape[1]}×{px.shape[0]})", flush=True)
    return px


class Steps:
    """A small state machine run by a timer: each state waits for Blender to redraw."""

    def __init__(self):
        self.start = time.perf_counter()
        self.draws = 0
        self.headers = []
        original_draw, original_text = ui.draw_omis, operators.progress_text

        def counting_draw(layout, context):
            self.draws += 1
            return original_draw(layout, context)

        def recording_text(job):
            text = original_text(job)
            self.headers.append(text)
            return text
        original_header = ui._draw_header
        self.header_draws = 0

        def counting_header(panel, context):
            if operators.running is not None:
                self.header_draws += 1
            return original_header(panel, context)
        ui.draw_omis = counting_draw
        operators.progress_text = recording_text
        ui._draw_header = counting_header
        self.plan = list(self.engine_steps('CYCLES', bpy.types.OMIS_PT_bake)) + \
            list(self.engine_steps('BLENDER_EEVEE', bpy.types.OMIS_PT_bake)) + \
            list(self.bake_steps())

    def redraw(self):
        window, area, region = properties_area()
        area.tag_redraw()
        region.tag_redraw()

    def engine_steps(self, engine, panel):
        def show():
            bpy.context.scene.render.engine = engine
            self.draws = 0
            self.redraw()
            window, area, region = properties_area()
            if area.spaces.active.context != 'RENDER':
                return "again"
            # The omis panel sits low in Render Properties: scroll to the end with the
            # mouse wheel over the editor.
            x, y = region.x + region.width // 2, region.y + region.height // 2
            window.event_simulate(type='MOUSEMOVE', value='NOTHING', x=x, y=y)
            for _ in range(60):
                window.event_simulate(type='WHEELDOWNMOUSE', value='PRESS', x=x, y=y)

        def shoot_with():
            U.check(self.draws > 0, f"{engine}: Blender never drew the omis panel")
            self.with_panel = screenshot(f"panel_{engine.lower()}")
            U.check(self.with_panel.std() > 0.01, f"{engine}: an empty screenshot")
            window, area, region = properties_area()
            with bpy.context.temp_override(window=window, area=area, region=region):
                U.check(bpy.ops.omis.bake.poll(), f"{engine}: the Bake operator is unreachable")
            bpy.utils.unregister_class(panel)
            self.redraw()

        def shoot_without():
            without = screenshot(f"no_panel_{engine.lower()}")
            bpy.utils.register_class(panel)
            self.redraw()
            U.check(without.shape == self.with_panel.shape, "the editor changed size")
            changed = np.any(np.abs(without - self.with_panel) > 0.02, axis=2).mean()
            print(f"{engine}: the panel changes {100 * changed:.1f} % of the editor", flush=True)
            U.check(changed > MIN_CHANGED, f"{engine}: the panel draws (almost) nothing: "
                                           f"{100 * changed:.2f} % of pixels changed")
        return (show, shoot_with, shoot_without)

    def bake_steps(self):
        def invoke():
            bpy.context.scene.render.engine = 'BLENDER_EEVEE'
            window, area, region = properties_area()
            with bpy.context.temp_override(window=window, area=area, region=region):
                result = bpy.ops.omis.bake('INVOKE_DEFAULT', samples=10 ** 6, time_budget=60.0)
            U.check(result == {'RUNNING_MODAL'}, f"invoke: {result}")
            self.job = operators.running
            self.headers.clear()

        def progress():
            job = self.job
            self.redraw()
            if job.fraction <= 0 or self.header_draws < 2 or \
                    not any("left" in h for h in self.headers):
                return "again"
            screenshot("baking_eevee")
            print(f"header while baking: {self.headers[-1]!r}", flush=True)
            window = bpy.context.window_manager.windows[0]
            window.event_simulate(type='ESC', value='PRESS')
            window.event_simulate(type='ESC', value='RELEASE')

        def cancelled():
            if operators.running is not None:
                return "again"
            U.check(self.job.cancelled, "Esc did not cancel the bake")
        return (invoke, progress, cancelled)

    def __call__(self):
        try:
            if time.perf_counter() - self.start > TIMEOUT:
                finish(1, f"FAIL: timeout ({len(self.plan)} steps left)")
            if not self.plan:
                finish(0, "ok test_panel_screenshot")
            if self.plan[0]() != "again":
                self.plan.pop(0)
            return 0.3
        except Exception:
            traceback.print_exc()
            finish(1, "FAIL test_panel_screenshot")


os.makedirs(OUT, exist_ok=True)
# Close the splash screen (--factory-startup shows it) so that it hides nothing.
for value in ('PRESS', 'RELEASE'):
    bpy.context.window_manager.windows[0].event_simulate(type='ESC', value=value)
build_scene()
properties_area()
bpy.app.timers.register(Steps(), first_interval=1.0)
