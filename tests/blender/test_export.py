"""Scene export: counts with modifiers and instances, visibility, transforms (against
closed forms), light units (SPEC §4), emission and world.

    scripts/blender_run.sh tests/blender/test_export.py
"""

import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

import omis_bake  # noqa: E402
from omis_bake import export, native  # noqa: E402

check = U.check
native.load()


def run_export(objects, target='IMAGE_TEXTURES'):
    bpy.context.view_layer.update()
    return export.export_scene(bpy.context, objects, target, omis=native.omis,
                               units=native.units)


def receiver(res=16, **kwargs):
    img = U.make_image("bake", res)
    ob = U.grid_mesh("Receiver", **kwargs)
    ob.data.materials.append(U.image_material("ReceiverMat", img))
    return ob, img


def test_counts_modifiers_instances_visibility():
    U.reset_scene()
    plane, _ = receiver(res=8, size=2.0, cuts=1)
    U.add_light('POINT', energy=100, location=(0, 0, 3), shadow_soft_size=0)

    cube = U.add_box("Subdivided", (0.5, 0.5, 0.5), (0, 0, 1))
    sub = cube.modifiers.new("Subdivision", 'SUBSURF')
    sub.levels = sub.render_levels = 2                       # 6·4² quads → 192 triangles

    props = bpy.data.collections.new("Props")                # not linked: instanced only
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1, radius=0.1)   # 20 triangles
    ico = bpy.context.active_object
    for c in ico.users_collection:
        c.objects.unlink(ico)
    props.objects.link(ico)
    for i in range(3):
        empty = U.link(bpy.data.objects.new(f"Instance{i}", None))
        empty.instance_type = 'COLLECTION'
        empty.instance_collection = props
        empty.location = (i - 1.0, 1.5, 0.5)

    hidden = U.add_box("HiddenRender", (0.2, 0.2, 0.2), (0, 0, 0.5))
    hidden.hide_render = True
    off = bpy.data.collections.new("RenderOff")
    bpy.context.scene.collection.children.link(off)
    off.hide_render = True
    in_off = bpy.data.objects.new("InRenderOff", cube.data)
    off.objects.link(in_off)
    viewport_hidden = U.add_box("ViewportHidden", (0.2, 0.2, 0.2), (0.5, 0, 0.5))
    viewport_hidden.hide_set(True)

    e = run_export([plane])
    counts = e.counts
    check(counts["triangles"] == 8 + 192 + 3 * 20,
          f"triangles {counts['triangles']} != plane 8 + subdivided cube 192 + 3×20 instances")
    check(counts["vertices"] == 9 + 98 + 3 * 12, f"vertices {counts['vertices']}")
    check(counts["instances"] == 1 + 1 + 3, f"instances {counts['instances']}")
    check(counts["lights"] == {"point": 1}, f"lights {counts['lights']}")
    check(any("ViewportHidden" in w for w in e.warnings),
          f"no warning for the viewport-hidden object: {e.warnings}")
    check(not any("HiddenRender" in w or "InRenderOff" in w for w in e.warnings),
          "render-disabled objects must be skipped silently")

    # Viewport and render settings differ: reported, the viewport evaluation is used.
    sub.levels = 1
    e = run_export([plane])
    check(counts_triangles(e) == 8 + 48 + 60, f"viewport levels not used: {counts_triangles(e)}")
    check(any("viewport levels" in w for w in e.warnings), f"no level warning: {e.warnings}")


def counts_triangles(e):
    return e.counts["triangles"]


def expected_point(world_points, normal, light_pos, intensity):
    w = light_pos[None, :] - world_points
    d2 = np.sum(w * w, axis=1)
    cos = np.maximum(0.0, (w @ normal) / np.sqrt(d2))
    return intensity * cos / d2 / math.pi


def texel_world_points(ob, size, res, du=0.0, dv=0.0):
    u = (np.arange(res) + 0.5 + du) / res
    v = (np.arange(res) + 0.5 + dv) / res
    uu, vv = np.meshgrid(u, v)                       # row 0 = v at the bottom
    local = np.stack([(uu - 0.5) * size, (vv - 0.5) * size, np.zeros_like(uu), np.ones_like(uu)],
                     axis=-1).reshape(-1, 4)
    M = np.array(ob.matrix_world)
    world = (local @ M.T)[:, :3]
    n = np.linalg.inv(M[:3, :3]).T @ np.array([0.0, 0.0, 1.0])
    return world, n / np.linalg.norm(n)


def test_transforms_against_closed_form():
    for mirrored in (False, True):
        U.reset_scene()
        res = 16
        plane, img = receiver(res=res, size=1.0, cuts=3)
        plane.location = (0.3, -0.2, 0.5)
        plane.rotation_euler = (U.deg(30), 0, U.deg(20))
        plane.scale = (-2.0 if mirrored else 2.0, 1.5, 1.0)
        light_pos = np.array([0.2, -1.1, 2.5])
        U.add_light('POINT', energy=500.0, location=tuple(light_pos), shadow_soft_size=0.0)
        bpy.context.view_layer.update()
        stats = omis_bake.bake(bpy.context, [plane], samples=256, margin=0)
        got = U.pixels(img)[..., :3].reshape(-1, 3)
        # Each texel is box-filtered over its footprint (the central half-texel
        # square, as Cycles): the closed form averaged over an 8 × 8 grid there.
        # Texels on a cell's diagonal (a triangle edge through their centres)
        # have part of their footprint mirrored back into their triangle, so
        # they are left out; 1e-3 allows the quadrature; a wrong transform is
        # off by far more.
        offsets = (np.arange(8) + 0.5) / 8 * 0.5 - 0.25
        want = 0.0
        for du in offsets:
            for dv in offsets:
                world, n = texel_world_points(plane, 1.0, res, du, dv)
                want = want + expected_point(world, n, light_pos, 500.0 / (4 * math.pi)) / 64
        texel = np.arange(res * res)
        cell = res // 4                                # cuts=3: 4 × 4 quads
        off_edges = (texel % res) % cell != (texel // res) % cell
        err = np.abs(got[off_edges, 0] - want[off_edges]).max() / want.max()
        check(err < 1e-3, f"mirrored={mirrored}: relative error {err} against the closed form")
        check(stats["exported"]["triangles"] == 32, stats["exported"])


def test_light_units():
    U.reset_scene()
    plane, _ = receiver(res=4, size=1.0, cuts=1)
    c = (1.0, 0.5, 0.25)
    U.add_light('POINT', "point", energy=1000.0, color=c, location=(0, 0, 2),
                shadow_soft_size=0.0)
    U.add_light('SPOT', "spot", energy=500.0, location=(1, 0, 2), rotation=(U.deg(20), 0, 0),
                spot_size=1.0, spot_blend=0.2, shadow_soft_size=0.05)
    U.add_light('SUN', "sun", energy=2.0, color=c, rotation=(0, U.deg(45), 0), angle=0.1)
    sq = U.add_light('AREA', "square", energy=100.0, location=(0, 1, 2), shape='SQUARE',
                     size=0.5, spread=U.deg(60))
    sq.scale = (2.0, 3.0, 1.0)
    U.add_light('AREA', "disk", energy=100.0, location=(0, -1, 2), shape='DISK', size=0.4)
    U.add_light('AREA', "ellipse", energy=100.0, location=(1, -1, 2), shape='ELLIPSE',
                size=0.4, size_y=0.2)
    rect = U.add_light('AREA', "rect", energy=100.0, location=(-1, -1, 2), shape='RECTANGLE',
                       size=0.4, size_y=0.2)
    rect.data.cycles.cast_shadow = False
    rect.data.cycles.use_multiple_importance_sampling = False
    U.constant_world("W", color=(0.2, 0.3, 0.4), strength=2.0)
    e = run_export([plane])
    by_id = {}
    for light in e.lights:
        by_id.setdefault(light["kind"], []).append(light)

    def close(a, b, tol=1e-6):
        return np.allclose(np.asarray(a, float), np.asarray(b, float), rtol=tol, atol=tol)

    (p,) = by_id["point"]
    check(close(p["intensity"], [1000 / (4 * math.pi) * k for k in c]), f"point {p}")
    check(p["radius"] == 0.0, "point radius")
    (s,) = by_id["spot"]
    check(close(s["intensity"], [500 / (4 * math.pi)] * 3), f"spot {s}")
    check(close(s["spot_size"], 1.0) and close(s["spot_blend"], 0.2) and close(s["radius"], 0.05),
          f"spot cone {s}")
    check(close(s["direction"], [0, math.sin(U.deg(20)), -math.cos(U.deg(20))], 1e-5),
          f"spot direction {s['direction']}")
    (sun,) = by_id["sun"]
    check(close(sun["irradiance"], [2 * k for k in c]) and close(sun["angle"], 0.1), f"sun {sun}")
    check(close(sun["direction"], [-math.sin(U.deg(45)), 0, -math.cos(U.deg(45))], 1e-5),
          f"sun direction {sun['direction']}")
    rects = {round(r["area"], 6): r for r in by_id["rect"]}
    square = rects[round(1.0 * 1.5, 6)]                        # (0.5·2) × (0.5·3)
    check(close(square["radiance"], [100 / (4 * 1.5)] * 3, 1e-5), f"scaled square {square}")
    check(close(square["spread"], U.deg(60), 1e-6), "spread")
    check(close(np.cross(square["axis_u"], square["axis_v"]) / 1.5, [0, 0, -1], 1e-5),
          "area light must emit toward its local -Z")
    r = rects[round(0.4 * 0.2, 6)]
    check(r.get("cast_shadow") is False and r.get("visible_to_bsdf") is False, f"flags {r}")
    areas = sorted(round(x["area"], 6) for x in by_id["ellipse"])
    check(areas == sorted([round(math.pi / 4 * 0.16, 6), round(math.pi / 4 * 0.08, 6)]),
          f"disk/ellipse areas {areas}")
    for x in by_id["ellipse"]:
        check(close(x["radiance"], [100 / (4 * x["area"])] * 3, 1e-5), f"ellipse {x}")
    (w,) = by_id["world"]
    check(close(w["radiance"], [0.4, 0.6, 0.8], 1e-6), f"world {w}")


def spec_value(kind):
    """SPEC §4 checked values: 1 m away, facing, DIFFUSE direct (E/π)."""
    U.reset_scene()
    plane, img = receiver(res=2, size=0.001, cuts=1)
    if kind == "point":
        U.add_light('POINT', energy=1000.0, location=(0, 0, 1), shadow_soft_size=0.0)
    elif kind == "area":
        U.add_light('AREA', energy=1000.0, location=(0, 0, 1), shape='SQUARE', size=0.1)
    else:
        U.add_light('SUN', energy=math.pi, angle=0.0)
    omis_bake.bake(bpy.context, [plane], samples=4096, margin=0)
    return float(U.pixels(img)[..., :3].mean())


def test_spec_reference_values():
    for kind, want, tol in (("point", 25.33, 0.001), ("area", 79.3, 0.002), ("sun", 1.000, 1e-4)):
        got = spec_value(kind)
        check(abs(got - want) / want < tol, f"{kind}: {got} vs SPEC {want}")
        print(f"  SPEC §4 {kind}: {got:.4f} (SPEC {want})")


def emission_material(name, color=(1, 0.5, 0.25, 1), strength=2.0, textured=False):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Emission"].default_value = color
    bsdf.inputs["Emission Strength"].default_value = strength
    if textured:
        tex = mat.node_tree.nodes.new("ShaderNodeTexNoise")
        mat.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Emission"])
    return mat


def test_emission_and_world():
    U.reset_scene()
    plane, _ = receiver(res=4, size=1.0, cuts=1)
    glow = U.add_box("Glow", (0.2, 0.2, 0.2), (0, 0, 1))
    glow.data.materials.append(emission_material("Glow"))
    tex = U.add_box("Textured", (0.2, 0.2, 0.2), (0.5, 0, 1))
    tex.data.materials.append(emission_material("TexturedGlow", textured=True))
    world = bpy.data.worlds.new("Sky")
    world.use_nodes = True
    env = world.node_tree.nodes.new("ShaderNodeTexSky")
    world.node_tree.links.new(env.outputs[0], world.node_tree.nodes["Background"].inputs[0])
    bpy.context.scene.world = world
    e = run_export([plane])
    check(e.counts["emissive_meshes"] == 1, f"emissive meshes {e.counts}")
    check(any("textured emission" in w and "TexturedGlow" in w for w in e.warnings),
          f"textured emission not reported: {e.warnings}")
    check(not any("background" in w for w in e.warnings), f"sky warned about: {e.warnings}")
    worlds = [l for l in e.lights if l["kind"] == "world"]
    check(e.counts["world"] and len(worlds) == 1 and worlds[0]["image_shape"][2] == 3,
          f"the sky must be exported as a world image: {worlds}")
    bpy.context.scene.world = None
    e = run_export([plane])
    check("world" not in e.counts["lights"], "no world → no world light")


def main():
    for test in (test_counts_modifiers_instances_visibility, test_transforms_against_closed_form,
                 test_light_units, test_spec_reference_values, test_emission_and_world):
        test()
        print(f"ok {test.__name__}")


main()
