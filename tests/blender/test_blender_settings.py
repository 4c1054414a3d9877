"""Issue 12 items 3 and 7: one set of settings, honoured or refused, and scripting that
agrees with the panel.

- Blender's own bake settings (scene.render.bake: target, margin, margin type, clear,
  selected to active) drive the bake; operator / bake() arguments override them.
- Selected to Active is refused with a message that names the setting and the way
  out; nothing is written. (Adjacent Faces margins: test_adjacent_margin.py.)
- bpy.ops.omis.bake(techniques=...) implies Manual sampling, as omis_bake.bake() does;
  objects may be given by name.

    scripts/blender_run.sh tests/blender/test_blender_settings.py
"""

import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

import omis_bake  # noqa: E402

check = U.check
MARK = (0.25, 0.5, 0.75, 0.5)
RES = 32


def setup(n_objects=1):
    """Planes whose UVs cover the middle half of their own image (room for a margin)."""
    U.reset_scene()
    objects, images = [], []
    for i in range(n_objects):
        img = U.make_image(f"img{i}", RES)
        U.set_pixels(img, MARK)
        ob = U.grid_mesh(f"Plane{i}", size=1.0, cuts=1, location=(1.2 * i, 0, 0),
                         uv_rect=(0.25, 0.25, 0.75, 0.75))
        ob.data.materials.append(U.image_material(f"mat{i}", img))
        objects.append(ob)
        images.append(img)
    U.add_light('AREA', "lamp", energy=300.0, location=(0.3, 0.2, 1.5), size=0.5)
    U.select_only(objects)
    return objects, images


def is_mark(px):
    return np.all(np.isclose(px, np.asarray(MARK, np.float32), atol=1e-6), axis=-1)


def expect_refusal(texts, images, **arguments):
    """Both entry points refuse with every text in the message and write nothing."""
    for call in ("bake", "operator"):
        try:
            if call == "bake":
                omis_bake.bake(bpy.context, samples=1, **arguments)
            else:
                bpy.ops.omis.bake(samples=1, **arguments)
        except (omis_bake.BakeError, RuntimeError) as exc:
            for text in texts:
                check(text in str(exc), f"{call}: expected {text!r} in {exc}")
        else:
            raise AssertionError(f"{call}: not refused ({texts})")
        for img in images:
            check(np.all(is_mark(U.pixels(img))), f"{call}: refused bake changed {img.name}")


def test_refusals():
    objects, images = setup(2)
    bpy.context.scene.render.bake.use_selected_to_active = True
    expect_refusal(["Selected to Active", "use_selected_to_active = False"], images)


def written(img):
    return ~is_mark(U.pixels(img))


def test_scene_output_settings():
    objects, images = setup()
    img = images[0]
    bake = bpy.context.scene.render.bake
    bake.margin_type = 'EXTEND'
    bake.use_clear = False
    sizes = {}
    for margin in (1, 3):
        U.set_pixels(img, MARK)
        bake.margin = margin
        omis_bake.bake(bpy.context, samples=1)
        sizes[margin] = int(written(img).sum())
    # The island covers 16×16 texels; a margin of m adds rings around it, and with
    # Clear off every texel beyond keeps its old value.
    island = (RES // 2) ** 2
    check(island < sizes[1] < sizes[3] < RES * RES,
          f"texels written with margin 1 / 3: {sizes} (island {island})")
    # The operator's argument overrides the scene's margin.
    U.set_pixels(img, MARK)
    bpy.ops.omis.bake(samples=1, margin=1)
    check(int(written(img).sum()) == sizes[1], "margin argument ignored")
    # Clear (the scene's): every texel is written, baked or cleared.
    bake.use_clear = True
    U.set_pixels(img, MARK)
    omis_bake.bake(bpy.context, samples=1)
    check(np.all(written(img)), "Clear Image of scene.render.bake ignored")

    # The scene's target: Blender's 'VERTEX_COLORS' bakes the active color attribute.
    me = objects[0].data
    attr = me.color_attributes.new("col", 'FLOAT_COLOR', 'POINT')
    me.color_attributes.active_color = attr
    bake.target = 'VERTEX_COLORS'
    U.set_pixels(img, MARK)
    stats = omis_bake.bake(bpy.context, samples=1)
    check(stats["target"] == 'COLOR_ATTRIBUTES' and stats["attributes"] == ["Plane0:col"],
          f"target from the scene: {stats['target']} {stats['attributes']}")
    check(np.all(is_mark(U.pixels(img))), "a color-attribute bake changed the image")
    bake.target = 'IMAGE_TEXTURES'


def test_scripting_agrees_with_panel():
    objects, images = setup(2)
    props = bpy.context.scene.omis
    check(props.technique_mode == 'AUTO', "the scene starts in Automatic sampling")

    def bake_image(call, **arguments):
        for img in images:
            U.set_pixels(img, MARK)
        if call == "operator":
            check(bpy.ops.omis.bake(samples=8, seed=5, margin=0, **arguments) == {'FINISHED'},
                  "operator")
        else:
            omis_bake.bake(bpy.context, samples=8, seed=5, margin=0, **arguments)
        return U.pixels(images[0]).copy()

    auto = bake_image("bake")
    from_bake = bake_image("bake", techniques=['BSDF'])
    from_operator = bake_image("operator", techniques={'BSDF'})
    check(np.array_equal(from_bake, from_operator),
          "operator(techniques=) and bake(techniques=) differ: one ignores the techniques")
    check(not np.array_equal(auto, from_operator),
          "techniques={'BSDF'} baked the Automatic choice (ignored)")
    check("bsdf" in props.last_plan and "solid-angle" not in props.last_plan,
          f"plan after techniques={{'BSDF'}}: {props.last_plan!r}")
    check(props.technique_mode == 'AUTO', "operator arguments changed the scene")
    # An explicit technique_mode still wins.
    bake_image("operator", techniques={'BSDF'}, technique_mode='AUTO')
    check(np.array_equal(U.pixels(images[0]), auto), "technique_mode='AUTO' not honoured")

    # Objects by name (a single name or a list); unknown names are refused.
    for img in images:
        U.set_pixels(img, MARK)
    stats = omis_bake.bake(bpy.context, objects=["Plane1"], samples=1, margin=0)
    check(stats["objects"] == ["Plane1"], f"objects {stats['objects']}")
    check(np.all(is_mark(U.pixels(images[0]))) and not np.all(is_mark(U.pixels(images[1]))),
          "objects=['Plane1'] did not bake exactly Plane1")
    stats = omis_bake.bake(bpy.context, objects="Plane0", samples=1, margin=0)
    check(stats["objects"] == ["Plane0"], f"objects {stats['objects']}")
    try:
        omis_bake.bake(bpy.context, objects=["Nope"], samples=1)
    except omis_bake.BakeError as exc:
        check("objects" in str(exc) and "Nope" in str(exc), str(exc))
    else:
        raise AssertionError("an unknown object name was not refused")


def test_margin_type_arguments():
    """A bad margin type is refused by name, in the add-on and in the omis module."""
    objects, images = setup()
    try:  # (the operator's enum argument refuses it itself, with Blender's TypeError)
        omis_bake.bake(bpy.context, samples=1, margin_type='SMEAR')
    except omis_bake.BakeError as exc:
        check("margin_type" in str(exc) and "ADJACENT_FACES" in str(exc), str(exc))
    else:
        raise AssertionError("bake() accepted margin_type='SMEAR'")
    check(np.all(is_mark(U.pixels(images[0]))), "a refused bake changed the image")
    from omis_bake import native
    omis = native.require()
    scene = omis.Scene()
    mesh = scene.add_mesh(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0]], np.float64),
                          np.array([[0, 1, 2]], np.uint32),
                          uvs=np.array([[0, 0], [1, 0], [1, 1]], np.float64))
    scene.commit()
    try:
        omis.bake_uv(scene, mesh, 8, 8, samples=1, margin_type="smear")
    except ValueError as exc:
        check("margin_type" in str(exc) and "adjacent-faces" in str(exc), str(exc))
    else:
        raise AssertionError("bake_uv accepted margin_type='smear'")


def main():
    for test in (test_refusals, test_scene_output_settings, test_scripting_agrees_with_panel,
                 test_margin_type_arguments):
        start = time.perf_counter()
        test()
        print(f"ok {test.__name__} ({time.perf_counter() - start:.2f} s)")


main()
