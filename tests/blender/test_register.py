"""Registration, operator and panel, settings through a saved .blend, the panel when
the native module is missing.

    scripts/blender_run.sh tests/blender/test_register.py
"""

import os
import sys

import addon_utils
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

import omis_bake  # noqa: E402
from omis_bake import native, settings  # noqa: E402

check = U.check


def registered():
    return (hasattr(bpy.types.Scene, "omis") and hasattr(bpy.types, "OMIS_OT_bake")
            and hasattr(bpy.types, "OMIS_PT_bake"))


def test_register_twice():
    check(registered(), "blender_run.sh should have enabled the add-on")
    for _ in range(2):
        addon_utils.disable("omis_bake", default_set=True)
        check(not hasattr(bpy.types.Scene, "omis"), "scene.omis left after unregister")
        check(not hasattr(bpy.types, "OMIS_OT_bake"), "operator left after unregister")
        check(not hasattr(bpy.types, "OMIS_PT_bake"), "panel left after unregister")
        mod = addon_utils.enable("omis_bake", default_set=True,
                                 handle_error=lambda e: (_ for _ in ()).throw(e))
        check(mod is not None and registered(), "enable did not register everything")
    check(addon_utils.check("omis_bake") == (True, True), "add-on not reported enabled")
    info = omis_bake.bl_info
    check(info["blender"] == (3, 4, 0) and info["category"] == "Render", f"bl_info {info}")


def test_operator_and_panel():
    op = bpy.ops.omis.bake
    props = op.get_rna_type().properties
    for name in settings.ARGUMENT_NAMES:
        check(name in props, f"operator lacks the argument {name}")
    check(op.idname() == "OMIS_OT_bake", op.idname())
    panel = bpy.types.OMIS_PT_bake
    # A panel of its own: inside Cycles' Bake panel it put two Bake buttons in one panel.
    check(not getattr(panel, "bl_parent_id", ""), "the panel sits inside another panel")
    check(panel.bl_context == "render" and panel.bl_space_type == 'PROPERTIES', "panel place")
    scene = bpy.context.scene
    for engine in ('BLENDER_EEVEE', 'BLENDER_WORKBENCH', 'CYCLES'):
        scene.render.engine = engine
        check(panel.poll(bpy.context), f"panel hidden with {engine}")
    check(scene.omis.use_optimal_mis is True, "the toggle must default to on")
    check(native.load() and native.origin == "PYTHONPATH" and native.error == "",
          f"native module: {native.origin} {native.error}")


NON_DEFAULT = {
    "use_optimal_mis": False, "optimal_mode": 'PROGRESSIVE', "heuristic": 'CUTOFF',
    "power_beta": 3.0, "cutoff_threshold": 0.25, "technique_mode": 'MANUAL',
    "techniques": {'BSDF', 'POWER_AREA', 'UNOCCLUDED_PARALLEL'}, "samples": 77,
    "time_budget": 12.5, "use_noise_target": True, "noise_target": 0.02, "seed": 99,
}


def test_settings_round_trip():
    check(set(NON_DEFAULT) == set(settings.SETTING_NAMES), "NON_DEFAULT must cover every setting")
    props = bpy.context.scene.omis
    for name, value in NON_DEFAULT.items():
        setattr(props, name, value)
    path = os.path.join(U.temp_dir(), "settings.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    for name in NON_DEFAULT:
        props.property_unset(name)
    check(props.samples != 77, "property_unset did not reset")
    bpy.ops.wm.open_mainfile(filepath=path)
    props = bpy.context.scene.omis
    for name, value in NON_DEFAULT.items():
        got = getattr(props, name)
        if isinstance(value, float):
            ok = abs(got - value) < 1e-6
        elif isinstance(value, set):
            ok = set(got) == value
        else:
            ok = got == value
        check(ok, f"{name}: saved {value!r}, loaded {got!r}")
    s = settings.settings_from(props)
    check(s.strategy == "cutoff" and s.technique_names() == ["bsdf", "power/area",
                                                             "unoccluded/parallel"],
          f"settings: {s.strategy} {s.technique_names()}")
    for name in NON_DEFAULT:
        props.property_unset(name)
    check(settings.settings_from(props).strategy == "optimal-direct", "defaults")


FakeLayout = U.FakeLayout


def draw_panel():
    log = []
    panel = bpy.types.OMIS_PT_bake
    fake = type("P", (), {"layout": FakeLayout(log)})()
    panel.draw(fake, bpy.context)
    return log


def test_panel_draw_and_missing_native():
    log = draw_panel()
    check(("operator", "omis.bake") in log, "no Bake button")
    for name in ("use_optimal_mis", "optimal_mode", "technique_mode", "samples", "time_budget",
                 "use_noise_target"):
        check(("prop", name) in log, f"panel does not show {name}")
    # The panel is its own under every engine: it shows the settings of
    # scene.render.bake it reads (Blender's own, not copies of them).
    for name in ("target", "margin", "margin_type", "use_clear"):
        check(("prop", name) in log, f"the panel does not show {name}")
    check([entry for entry in log if entry[0] == "operator"] == [("operator", "omis.bake")],
          f"one Bake button expected: {log}")
    check(not any("not available" in text for kind, text in log if kind == "label"),
          "panel reports a missing module although it loaded")

    # A missing native module: the panel says why, the bake reports it, nothing raises.
    saved = (native.omis, native.units, native.error, native.load)
    native.omis, native.units = None, None
    native.error = "the native module 'omis' is not installed: test"
    native.load = lambda: False
    try:
        log = draw_panel()
        labels = " ".join(text for kind, text in log if kind == "label")
        check("not available" in labels and "not installed" in labels,
              f"panel does not explain the missing module: {labels!r}")
        try:
            omis_bake.bake(bpy.context, [])
        except omis_bake.BakeError as exc:
            check("not installed" in str(exc), f"bake error: {exc}")
        else:
            raise AssertionError("bake without the native module did not fail")
        try:
            bpy.ops.omis.bake()
        except RuntimeError as exc:
            check("not installed" in str(exc), f"operator error: {exc}")
        else:
            raise AssertionError("operator without the native module did not report an error")
    finally:
        native.omis, native.units, native.error, native.load = saved


def main():
    for test in (test_register_twice, test_operator_and_panel, test_settings_round_trip,
                 test_panel_draw_and_missing_native):
        test()
        print(f"ok {test.__name__}")


main()
