"""Issue 12 items 5 and 6, with Blender's interface (virtual X server): the panel as
Blender draws it under Cycles and under EEVEE — one Render Properties panel of its
own under both, not inside Cycles' Bake panel —, screenshots of it, and a bake
started from it showing its progress and time left in the panel's header.

Issue 38 item 4: in the default layout's own Properties editor at its default width
(a 1920×1080 screen), after a bake from the Bake button that ignored settings, the
Last bake box lists its warnings (folded, then all) and every text fits its room
(panel_fit.py: each text's width in Blender's UI font against the room Blender's
layout gives it); the header while baking holds the panel's name and the progress.
The bake's reports in the Info editor: the warnings after the summary, at WARNING level,
and a warning last (what the status bar shows). Screenshots of each.

For each engine: Blender itself must call the panel's draw, the Bake operator must be
reachable from the Properties editor, and a screenshot with the panel must differ
clearly from one without it (the panel's region is not empty) — no pixel-exact
comparison. Screenshots go to <build>/test_screenshots/ for a person to look at.

    scripts/blender_run.sh --ui --screen 1920x1080 tests/blender/test_panel_screenshot.py
"""

import os
import sys
import time
import traceback

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402
import panel_fit  # noqa: E402

from omis_bake import operators, ui  # noqa: E402

TIMEOUT = 180.0
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
    return window, area, render_tab(area)


def default_properties_area():
    """The Properties editor of Blender's default layout (the narrowest one: the
    largest area became another), showing Render Properties."""
    window = bpy.context.window_manager.windows[0]
    area = min((a for a in window.screen.areas if a.type == 'PROPERTIES'),
               key=lambda a: a.width)
    return window, area, render_tab(area)


def render_tab(area):
    """Shows Render Properties in a Properties area; returns its main region. The
    editor's tabs exist once it has been drawn: the tab is set on a later call."""
    space = area.spaces.active
    try:
        if space.context != 'RENDER':
            space.context = 'RENDER'
    except TypeError:
        pass
    return next(r for r in area.regions if r.type == 'WINDOW')


def info_area():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type in ('OUTLINER', 'INFO'))
    return window, area, next(r for r in area.regions if r.type == 'WINDOW')


def scroll_to_end(where):
    """Mouse wheel over the editor until its end (the omis panel sits low)."""
    window, area, region = where()
    x, y = region.x + region.width // 2, region.y + region.height // 2
    window.event_simulate(type='MOUSEMOVE', value='NOTHING', x=x, y=y)
    for _ in range(60):
        window.event_simulate(type='WHEELDOWNMOUSE', value='PRESS', x=x, y=y)


def screenshot(name, where=properties_area):
    window, area, region = where()
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
        original_header = ui._draw_header_progress
        self.header_draws = 0

        def counting_header(panel, context):
            if operators.running is not None:
                self.header_draws += 1
            return original_header(panel, context)
        ui.draw_omis = counting_draw
        operators.progress_text = recording_text
        ui._draw_header_progress = counting_header
        self.plan = list(self.engine_steps('CYCLES', bpy.types.OMIS_PT_bake)) + \
            list(self.engine_steps('BLENDER_EEVEE', bpy.types.OMIS_PT_bake)) + \
            list(self.bake_steps()) + list(self.default_width_steps()) + \
            list(self.header_steps())

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

    def fits(self, label):
        """Every text of the panel fits its room in the default Properties editor."""
        window, area, region = default_properties_area()
        with bpy.context.temp_override(window=window, area=area, region=region):
            too_long = panel_fit.overflows(ui.draw_omis, region.width)
        print(f"{label}: region {region.width} px wide, texts too long: {too_long}", flush=True)
        U.check(not too_long, f"{label}: texts wider than their room: {too_long}")

    def redraw_all(self):
        for area in bpy.context.window_manager.windows[0].screen.areas:
            area.tag_redraw()

    def default_width_steps(self):
        """A bake with warnings from the Bake button, in the default Properties editor."""
        def invoke():
            U.ignored_settings_scene()
            bpy.context.scene.omis.show_all_warnings = False
            window, area, region = default_properties_area()
            U.check(region.width < 400, f"the default Properties editor is {region.width} px")
            with bpy.context.temp_override(window=window, area=area, region=region):
                result = bpy.ops.omis.bake('INVOKE_DEFAULT', samples=16)
            U.check(result == {'RUNNING_MODAL'}, f"invoke: {result}")

        def finished():
            if operators.running is not None:
                return "again"
            props = bpy.context.scene.omis
            warnings = [w for w in props.last_warnings.split("\n") if w]
            U.check(props.last_status == "complete" and len(warnings) > ui.FIRST_WARNINGS,
                    f"the bake: {props.last_status}, warnings {warnings}")
            scroll_to_end(default_properties_area)
            self.draws = 0
            self.redraw_all()

        def folded():
            if self.draws == 0:
                return "again"
            screenshot("panel_default_width", default_properties_area)
            self.fits("warnings folded")
            bpy.context.scene.omis.show_all_warnings = True
            scroll_to_end(default_properties_area)
            self.redraw_all()

        def unfolded():
            screenshot("panel_default_width_all_warnings", default_properties_area)
            # The Outliner becomes an Info editor for a moment: the bake's reports.
            info_area()[1].type = 'INFO'
            self.redraw_all()
            self.fits("warnings listed")
            props = bpy.context.scene.omis
            props.show_all_warnings = False

        def reports():
            """Each warning at WARNING level (the Info editor's screenshot shows their
            icons), after the summary, and a warning last: the status bar's banner
            shows the last report."""
            screenshot("info_after_bake", info_area)
            window, area, region = info_area()
            with bpy.context.temp_override(window=window, area=area, region=region):
                bpy.ops.info.select_all(action='SELECT')
                bpy.ops.info.report_copy()
            area.type = 'OUTLINER'
            lines = bpy.context.window_manager.clipboard.strip().split("\n")
            lines = lines[next(i for i, t in enumerate(lines) if t.startswith("bpy.ops.omis")):]
            warnings = bpy.context.scene.omis.last_warnings.split("\n")
            summary = next(i for i, t in enumerate(lines) if t.startswith("omis bake: "))
            print("reports:\n  " + "\n  ".join(lines), flush=True)
            U.check(f"complete, with {len(warnings)} warnings" in lines[summary], lines[summary])
            U.check(lines[summary + 1:-1] == warnings, "the warnings do not follow the summary")
            U.check(lines[-1].startswith(f"omis bake complete, with {len(warnings)} warnings"),
                    f"the last report is not the warnings' summary: {lines[-1]}")
        return (invoke, finished, folded, unfolded, reports)

    def header_steps(self):
        """The header while baking and a wrapped refusal, in the default Properties editor."""
        def start():
            # A shorter panel (no Last bake box) keeps its header in view while baking.
            props = bpy.context.scene.omis
            props.last_status = ""
            window, area, region = default_properties_area()
            with bpy.context.temp_override(window=window, area=area, region=region):
                result = bpy.ops.omis.bake('INVOKE_DEFAULT', samples=10 ** 6, time_budget=60.0)
            U.check(result == {'RUNNING_MODAL'}, f"invoke: {result}")
            self.job = operators.running
            self.header_draws = 0
            scroll_to_end(default_properties_area)

        def header():
            self.redraw_all()
            job = self.job
            if job.fraction <= 0 or self.header_draws < 2 or job.seconds_left() is None:
                return "again"
            screenshot("baking_default_width", default_properties_area)
            window, area, region = default_properties_area()
            text = operators.header_text(job)
            needed, room = panel_fit.header_fits(bpy.types.OMIS_PT_bake.bl_label, text,
                                                 region.width)
            print(f"header while baking: {text!r}, {needed:.0f} of {room:.0f} px", flush=True)
            U.check(needed <= room, f"the header needs {needed:.0f} px of {room:.0f}")
            window.event_simulate(type='ESC', value='PRESS')
            window.event_simulate(type='ESC', value='RELEASE')

        def cancelled():
            if operators.running is not None:
                return "again"
            U.check(self.job.cancelled, "Esc did not cancel the bake")
            # A refusal, wrapped: Selected to Active.
            bpy.context.scene.render.bake.use_selected_to_active = True
            self.redraw_all()

        def refusal():
            screenshot("refusal_default_width", default_properties_area)
            self.fits("refusal")
            bpy.context.scene.render.bake.use_selected_to_active = False
        return (start, header, cancelled, refusal)

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
