"""Issue 38 items 3–5, headless: warnings where the artist looks, a panel whose text
fits the default Properties width, the bake target among several Image Texture
nodes, UDIM images, the add-on's location text and the per-vertex wording.

    scripts/blender_run.sh tests/blender/test_panel_truth.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402
import panel_fit  # noqa: E402

import omis_bake  # noqa: E402
from omis_bake import job as job_module, operators, ui  # noqa: E402

check = U.check
# The default Properties editor's panel region (Blender 3.4's layout, 1920×1080), and
# the same layout on a 1600×900 screen (the areas scale with the window).
DEFAULT_WIDTH = ui.DEFAULT_REGION_WIDTH
NARROW_WIDTH = 247
# Each a setting the bake ignores, and a word of the warning that must say so.
EXPECTED = {
    "normal map": "Normal is linked",
    "textured metallic": "Metallic is linked",
    "guessed target": "no Image Texture node is active",
    "light node tree": "node tree is ignored",
    "occluder transparency": "transparency",
}


def panel_labels():
    out = []
    for text, _, _ in panel_fit.texts(ui.draw_omis, DEFAULT_WIDTH):
        out.append(text)
    return out


def test_warnings_where_the_artist_looks():
    floor, target, normal_img = U.ignored_settings_scene()
    before = U.pixels(normal_img).copy()
    props = bpy.context.scene.omis
    props.show_all_warnings = False
    stats = omis_bake.bake(bpy.context, samples=4)
    warnings = stats["warnings"]
    for what, words in EXPECTED.items():
        check(sum(words in w for w in warnings) == 1, f"{what}: not warned once: {warnings}")
    # The bake went into the one Image Texture node not linked to the shader.
    check(U.pixels(target)[..., :3].max() > 0, "the bake target stayed black")
    check(np.array_equal(U.pixels(normal_img), before), "the normal-map texture was changed")

    # The panel: how many, the first ones, the rest on demand.
    check(props.last_warnings.split("\n") == warnings, "scene.omis keeps every warning")
    n = len(warnings)
    text = " ".join(panel_labels())
    check(f"complete, with {n} warnings" in text, f"no status with {n} warnings: {text}")
    first = ui.FIRST_WARNINGS
    for w in warnings[:first]:
        check(" ".join(w.split()) in text, f"a first warning is not shown: {w}")
    for w in warnings[first:]:
        check(w not in text, f"a later warning shown before asked for: {w}")
    check(f"{n - first} more warnings" in text, f"no '{n - first} more warnings': {text}")
    props.show_all_warnings = True
    text = " ".join(panel_labels())
    for w in warnings:
        check(w in text, f"a warning is missing from the expanded list: {w}")
    check("Show fewer" in text, "no way to fold the list again")
    # Everything fits the default width, the expanded list included, and a narrower one.
    for width in (DEFAULT_WIDTH, NARROW_WIDTH):
        too_long = panel_fit.overflows(ui.draw_omis, width)
        check(not too_long, f"{width} px: texts wider than their room: {too_long}")
    props.show_all_warnings = False
    return stats


class RecordingOperator:
    def __init__(self):
        self.reports = []

    def report(self, level, text):
        self.reports.append((set(level), text))


def test_operator_reports(stats):
    """Each warning at WARNING level, and a warning last: Blender's status bar shows
    the last report."""
    op = RecordingOperator()
    operators._report_stats(op, stats)
    warned = [text for level, text in op.reports if level == {'WARNING'}]
    for w in stats["warnings"]:
        check(w in warned, f"not reported as a warning: {w}")
    check(op.reports[-1][0] == {'WARNING'}, f"the last report is not a warning: {op.reports[-1]}")
    n = len(stats["warnings"])
    check(f"with {n} warnings" in op.reports[-1][1], op.reports[-1][1])
    summary = [text for level, text in op.reports if level == {'INFO'}]
    check(any(f"complete, with {n} warnings" in t for t in summary), f"{summary}")
    # A bake without warnings ends on its summary.
    op = RecordingOperator()
    operators._report_stats(op, dict(stats, warnings=[]))
    check(op.reports[-1][0] == {'INFO'} and "(complete)" in op.reports[-1][1], op.reports)


def test_new_warnings_show_up():
    """Any warning string the bake returns reaches the panel (later bake statistics too)."""
    original = job_module.BakeJob.stats
    news = "12 texels of Floor lie inside other objects"

    def with_new_warning(self):
        stats = original(self)
        stats["warnings"].append(news)
        return stats
    job_module.BakeJob.stats = with_new_warning
    try:
        U.ignored_settings_scene()
        stats = omis_bake.bake(bpy.context, samples=1)
    finally:
        job_module.BakeJob.stats = original
    props = bpy.context.scene.omis
    check(news in props.last_warnings.split("\n"), "the new warning is not kept")
    props.show_all_warnings = True
    text = " ".join(panel_labels())
    props.show_all_warnings = False
    check(news in text and f"with {len(stats['warnings'])} warnings" in text, text)


def two_image_material(name, linked):
    """A material with two Image Texture nodes, the BSDF active; `linked` names the ones
    wired into the shader (A through a Normal Map, B into Base Color)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    for node_name in ("A", "B"):
        node = nodes.new("ShaderNodeTexImage")
        node.name = node_name
        node.image = U.make_image(f"{name}_{node_name}", 16)
        if node_name in linked:
            bsdf = nodes["Principled BSDF"]
            if node_name == "A":
                nm = nodes.new("ShaderNodeNormalMap")
                mat.node_tree.links.new(node.outputs["Color"], nm.inputs["Color"])
                mat.node_tree.links.new(nm.outputs["Normal"], bsdf.inputs["Normal"])
            else:
                mat.node_tree.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
    nodes.active = nodes["Principled BSDF"]
    return mat


def refusal(objects):
    try:
        omis_bake.bake(bpy.context, objects, samples=1)
    except omis_bake.BakeError as exc:
        return str(exc)
    raise AssertionError("the bake was not refused")


def test_bake_target_and_udim():
    U.reset_scene()
    U.add_light('SUN', "sun", energy=2.0)
    for linked, chosen in ((("A",), "B"), (("B",), "A")):
        U.reset_scene()
        U.add_light('SUN', "sun", energy=2.0)
        ob = U.grid_mesh("Plane", size=1.0)
        mat = two_image_material("M", linked)
        ob.data.materials.append(mat)
        U.select_only([ob])
        stats = omis_bake.bake(bpy.context, samples=1)
        check(stats["images"] == [f"M_{chosen}"], f"baked into {stats['images']}, not M_{chosen}")
    # Neither (or both) linked: a refusal naming the candidates and how to choose.
    for linked in ((), ("A", "B")):
        U.reset_scene()
        U.add_light('SUN', "sun", energy=2.0)
        ob = U.grid_mesh("Plane", size=1.0)
        ob.data.materials.append(two_image_material("M", linked))
        U.select_only([ob])
        message = refusal([ob])
        check('"A"' in message and '"B"' in message and "click the one to bake into" in message,
              message)
    # UDIM: refused with what to do instead.
    U.reset_scene()
    U.add_light('SUN', "sun", energy=2.0)
    tiled = bpy.data.images.new("tiles", 16, 16, float_buffer=True, tiled=True)
    ob = U.grid_mesh("Plane", size=1.0)
    ob.data.materials.append(U.image_material("m", tiled))
    U.select_only([ob])
    message = refusal([ob])
    check("UDIM" in message and "single (non-tiled) image" in message, message)


def test_more_ignored_settings():
    """A displacement, an emitter hidden from diffuse rays, a Transparent BSDF: warned."""
    U.reset_scene()
    img = U.make_image("t", 16)
    ob = U.image_grid("Plane", img, size=1.0)
    mat = ob.data.materials[0]
    bump = mat.node_tree.nodes.new("ShaderNodeDisplacement")
    mat.node_tree.links.new(bump.outputs[0],
                            mat.node_tree.nodes["Material Output"].inputs["Displacement"])
    glow = U.grid_mesh("Glow", size=0.5, location=(0, 0, 1))
    glow.rotation_euler = (3.14159, 0, 0)
    glow.data.materials.append(U.emission_material("Glow", strength=5.0))
    glow.visible_diffuse = False
    veil = U.grid_mesh("Veil", size=0.3, location=(0, 0, 0.5))
    veil_mat = bpy.data.materials.new("Veil")
    veil_mat.use_nodes = True
    nodes = veil_mat.node_tree.nodes
    clear = nodes.new("ShaderNodeBsdfTransparent")
    veil_mat.node_tree.links.new(clear.outputs[0], nodes["Material Output"].inputs["Surface"])
    veil.data.materials.append(veil_mat)
    U.select_only([ob])
    warnings = omis_bake.bake(bpy.context, samples=1)["warnings"]
    for words in ("Displacement) is ignored", '"Glow" emits light but is invisible',
                  'material "Veil": its transparency'):
        check(any(words in w for w in warnings), f"{words!r} not warned: {warnings}")


def test_vertex_wording():
    U.reset_scene()
    ob = U.grid_mesh("Plane", size=1.0, cuts=2)
    ob.data.color_attributes.new("Col", 'FLOAT_COLOR', 'POINT')
    U.add_light('SUN', "sun", energy=2.0)
    U.select_only([ob])
    stats = omis_bake.bake(bpy.context, samples=2, target='COLOR_ATTRIBUTES')
    text = " ".join(panel_labels())
    check("per vertex" in text and "95 % of vertices" in text and "texel" not in text, text)
    op = RecordingOperator()
    operators._report_stats(op, stats)
    line = next(t for level, t in op.reports if "samples per" in t)
    check("samples per vertex" in line and "95 % of vertices" in line, line)


def test_location_and_fit():
    panel = bpy.types.OMIS_PT_bake
    location = omis_bake.bl_info["location"]
    check("Render" in location and panel.bl_label in location and panel.bl_context == "render",
          f"location {location!r} does not say where the panel {panel.bl_label!r} is")
    # A refusal is wrapped, every word kept, and fits; so do the settings that show
    # only with Least Noise off (Cutoff) and Manual sampling (every method's label).
    props = bpy.context.scene.omis
    props.use_optimal_mis, props.heuristic, props.technique_mode = False, 'CUTOFF', 'MANUAL'
    bpy.context.scene.render.bake.use_selected_to_active = True
    try:
        reason = omis_bake.settings.settings_from(bpy.context.scene.omis).unsupported()
        shown = panel_fit.texts(ui.draw_omis, DEFAULT_WIDTH)
        too_long = [t for width in (DEFAULT_WIDTH, NARROW_WIDTH)
                    for t in panel_fit.overflows(ui.draw_omis, width)]
    finally:
        bpy.context.scene.render.bake.use_selected_to_active = False
        for name in ("use_optimal_mis", "heuristic", "technique_mode"):
            props.property_unset(name)
    # (a word too long for a line, a Python path, is cut: compare without spaces)
    check("".join(reason.split()) in "".join("".join(t for t, _, _ in shown).split()),
          "the refusal lost words")
    check(not too_long, f"texts wider than their room: {too_long}")
    # The header while baking: the panel's name and the longest progress text.
    # (the longest progress at the default width; a common one at the narrower width)
    for width, progress in ((DEFAULT_WIDTH, "100 %, 23:59:59 left"),
                            (NARROW_WIDTH, "42 %, 59:59 left")):
        needed, room = panel_fit.header_fits(panel.bl_label, progress, width)
        check(needed <= room, f"{width} px: the header needs {needed:.0f} px of {room:.0f}")


def test_clock():
    check([operators.clock(t) for t in (0.4, 12, 59.4, 60, 185, 3599, 3600, 7805)] ==
          ["0 s", "12 s", "59 s", "1:00", "3:05", "59:59", "1:00:00", "2:10:05"], "clock")


def main():
    stats = test_warnings_where_the_artist_looks()
    print("ok test_warnings_where_the_artist_looks")
    test_operator_reports(stats)
    print("ok test_operator_reports")
    for test in (test_new_warnings_show_up, test_bake_target_and_udim,
                 test_more_ignored_settings, test_vertex_wording, test_location_and_fit,
                 test_clock):
        test()
        print(f"ok {test.__name__}")


main()
