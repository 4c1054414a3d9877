"""The main job inside Blender: build the demo room with bpy, bake its floor
lightmap with the omis_bake add-on twice at equal time — optimal MIS and the
balance heuristic — and write the images, a noise comparison and the table.

    bash scripts/blender_run.sh scripts/blender_demo.py --out out/demo [--seconds S] [--size N]

The room is the one of bindings/omis/demo.py (same meshes, built from the same
functions); its two rectangular lights become Blender AREA lights whose Cycles
3.4 units give the same radiance: L = P·c/(4A), so P = 4·A·L; Blender area
lights emit along their local −Z.

Writes into --out: balance.exr|png, optimal.exr|png (Standard view, plus
_filmic.png), noise_comparison.png, table.txt.
"""

import argparse
import math
import os
import sys
import time

import bpy
import numpy as np

import omis
import omis.demo
import omis_bake
from omis_bake.job import BakeJob
from omis_bake.settings import settings_from

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "tests", "blender"))
from demo_bake import noise_comparison  # noqa: E402  (one plot for both demos)
# Argument, log and image-material functions shared with the Blender tests.
from omis_test_utils import args as script_args, image_material, log, make_image  # noqa: E402


# -- the scene -----------------------------------------------------------------

def reset_scene():
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.lights, bpy.data.materials,
                       bpy.data.images, bpy.data.cameras, bpy.data.collections):
        for item in list(collection):
            collection.remove(item)
    scene = bpy.context.scene
    scene.world = None                  # no world light, as omis.demo
    scene.render.engine = 'CYCLES'
    scene.cycles.use_denoising = False  # this Blender has no OpenImageDenoise
    return scene


def mesh_object(name, vertices, triangles, uvs=None):
    """A mesh object from (V,3) vertices and (T,3) triangles; optional (3T,2) corner UVs."""
    vertices = np.asarray(vertices, np.float32)
    triangles = np.asarray(triangles, np.int32)
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(vertices))
    me.vertices.foreach_set("co", vertices.ravel())
    me.loops.add(3 * len(triangles))
    me.loops.foreach_set("vertex_index", triangles.ravel())
    me.polygons.add(len(triangles))
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * len(triangles), 3, dtype=np.int32))
    me.polygons.foreach_set("loop_total", np.full(len(triangles), 3, np.int32))
    if uvs is not None:
        layer = me.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", np.asarray(uvs, np.float32).ravel())
    me.update(calc_edges=True)
    me.validate()
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def area_light(name, corner, edge_u, edge_v, radiance):
    """A Blender RECTANGLE area light equal to omis' add_rect_light(corner, edge_u,
    edge_v, radiance), which emits toward edge_u × edge_v: Blender's local X along
    edge_u, local Y along ±edge_v, local −Z along the emission direction, and
    energy P = 4·A·L with color L / max(L)."""
    corner, eu, ev = (np.asarray(a, float) for a in (corner, edge_u, edge_v))
    emit = np.cross(eu, ev)
    emit /= np.linalg.norm(emit)
    x = eu / np.linalg.norm(eu)
    z = -emit
    y = np.cross(z, x)                   # right-handed; ±edge_v direction
    rot = np.stack([x, y, z], axis=1)    # columns: local axes in world space
    radiance = np.asarray(radiance, float)
    area = float(np.linalg.norm(eu) * np.linalg.norm(ev))
    peak = float(radiance.max())
    data = bpy.data.lights.new(name, 'AREA')
    data.shape = 'RECTANGLE'
    data.size = float(np.linalg.norm(eu))
    data.size_y = float(np.linalg.norm(ev))
    data.energy = 4.0 * area * peak
    data.color = tuple(radiance / peak)
    data.spread = math.pi
    ob = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(ob)
    from mathutils import Matrix
    m = Matrix.Identity(4)
    for i in range(3):
        for j in range(3):
            m[i][j] = rot[i, j]
    m.translation = tuple(corner + 0.5 * (eu + ev))
    ob.matrix_world = m
    return ob


def build_demo(size):
    """The demo room of bindings/omis/demo.py in bpy; returns (floor object, its image)."""
    reset_scene()
    d = omis.demo
    floor_v, floor_t, floor_uv = d.grid(6.0, 6.0, 12)
    floor = mesh_object("Floor", floor_v, floor_t, floor_uv)
    image = make_image("FloorLightmap", size)
    floor.data.materials.append(image_material("FloorMat", image))

    room_h = 2.6
    boxes = [("WallN", (0, 3.05, room_h / 2), (6.2, 0.1, room_h)),
             ("WallS", (0, -3.05, room_h / 2), (6.2, 0.1, room_h)),
             ("WallE", (3.05, 0, room_h / 2), (0.1, 6.2, room_h)),
             ("WallW", (-3.05, 0, room_h / 2), (0.1, 6.2, room_h)),
             ("Ceiling", (0, 0, room_h + 0.05), (6.2, 6.2, 0.1)),
             ("TableTop", (-0.6, -0.2, 0.74), (1.6, 0.9, 0.04)),
             ("Cabinet", (2.2, 1.3, 0.6), (0.5, 0.6, 1.2))]
    boxes += [(f"Leg{i}", (lx, ly, 0.36), (0.05, 0.05, 0.72))
              for i, (lx, ly) in enumerate((lx, ly) for lx in (-1.3, 0.1) for ly in (-0.6, 0.2))]
    for name, center, extent in boxes:
        v, t = d.box(center, extent)
        mesh_object(name, v, t)

    area_light("CeilingLight", corner=(-1.2, -0.5, 2.2), edge_u=(0, 0.6, 0),
               edge_v=(1.2, 0, 0), radiance=(9.0, 9.0, 9.0))
    area_light("WallLight", corner=(2.95, 1.0, 1.2), edge_u=(0, 0, 0.5), edge_v=(0, 0.8, 0),
               radiance=(24.0, 18.0, 12.0))
    bpy.context.view_layer.update()
    return floor, image


# -- baking --------------------------------------------------------------------

def progress_printer(label):
    """Prints a progress bar line every 10 % (Blender's log is not a terminal)."""
    start = time.monotonic()
    shown = [-1]

    def show(fraction):
        step = int(fraction * 10)
        if step != shown[0]:
            shown[0] = step
            filled = int(30 * fraction)
            log(f"  {label:<16} [{'#' * filled}{'.' * (30 - filled)}] {100 * fraction:5.1f}%  "
                f"{time.monotonic() - start:5.1f}s")
        return True

    return show


def bake(floor, label, seconds, **settings):
    """omis_bake.bake(...) with the job kept: returns (stats, noise map, mask)."""
    for ob in bpy.context.view_layer.objects:
        ob.select_set(ob == floor)
    bpy.context.view_layer.objects.active = floor
    # The same steps as omis_bake.bake(context, objects, **settings), keeping the
    # job so that its per-texel noise estimate can be plotted.
    s = settings_from(bpy.context.scene.omis,
                      dict(samples=1 << 30, time_budget=seconds, seed=1, margin=16,
                           margin_type='EXTEND', **settings))
    job = BakeJob(bpy.context, [floor], s)
    job.run(progress=progress_printer(label))
    stats = job.finish(bpy.context)
    (unit,) = job.units
    return stats, unit.noise.copy(), unit.mask.copy()


def save_image(image, path_base, scene):
    """Linear float EXR and display PNGs (Standard, Filmic) via Blender's writers."""
    settings = scene.render.image_settings
    vs = scene.view_settings
    settings.file_format = 'OPEN_EXR'
    settings.color_depth = '32'
    settings.exr_codec = 'ZIP'
    image.save_render(path_base + ".exr", scene=scene)      # float data: written linear
    settings.file_format = 'PNG'
    settings.color_mode = 'RGB'
    settings.color_depth = '8'
    for view, suffix in (("Standard", ""), ("Filmic", "_filmic")):
        scene.display_settings.display_device = 'sRGB'
        vs.view_transform = view
        vs.look = 'None'
        vs.exposure = 0.0
        vs.gamma = 1.0
        image.save_render(path_base + suffix + ".png", scene=scene)


def main():
    parser = argparse.ArgumentParser(prog="blender_demo.py", description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/demo", help="output folder")
    parser.add_argument("--seconds", type=float, default=6.0,
                        help="bake time budget per strategy (s)")
    parser.add_argument("--size", type=int, default=256, help="lightmap resolution")
    parser.add_argument("--techniques", default=None,
                        help="comma-separated techniques instead of the effect plan's choice "
                             "(e.g. bsdf,unoccluded/solid-angle,power/area: with one technique, "
                             "the plan's choice for this room, both strategies weigh alike)")
    args = parser.parse_args(script_args())
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)

    log(f"Blender {bpy.app.version_string}, omis {omis.__version__} "
        f"(add-on from {os.path.dirname(omis_bake.__file__)})")
    floor, image = build_demo(args.size)
    log(f"demo scene built in Blender: {len(bpy.data.objects)} objects "
        f"(floor 6×6 m, walls, ceiling, table, 4 legs, cabinet; 2 area lights), "
        f"floor image {args.size}×{args.size}")
    log(f"baking the floor for {args.seconds:g} s per strategy")

    scene = bpy.context.scene
    runs = [("balance", "balance", dict(use_optimal_mis=False, heuristic='BALANCE')),
            ("optimal-direct", "optimal", dict(use_optimal_mis=True, optimal_mode='DIRECT'))]
    if args.techniques:
        for _, _, settings in runs:
            settings.update(technique_mode='MANUAL', techniques=set(args.techniques.split(",")))
    stats, maps = [], []
    for label, name, settings in runs:
        s, noise, mask = bake(floor, label, args.seconds, **settings)
        save_image(image, os.path.join(out, name), scene)
        stats.append(s)
        maps.append((noise, mask))
        if s["warnings"]:
            log(f"  warnings: {s['warnings']}")
    log("effect plan:\n" + stats[-1]["plan"])
    noise_comparison(os.path.join(out, "noise_comparison.png"), maps,
                     [label for label, _, _ in runs], stats)

    lines = ["", f"{'strategy':<16} {'time (s)':>9} {'samples/texel':>14} "
                 f"{'mean rel. error':>16} {'max rel. error':>15}"]
    for (label, _, _), s in zip(runs, stats):
        lines.append(f"{label:<16} {s['seconds']:>9.2f} {s['samples_per_texel']:>14.1f} "
                     f"{100 * s['mean_relative_error']:>15.2f}% "
                     f"{100 * s['max_relative_error']:>14.1f}%")
    b, o = (s["mean_relative_error"] for s in stats)
    lines.append(f"\nat equal time, optimal MIS leaves {o / b:.2f}× the relative error of the "
                 f"balance heuristic ({(o / b) ** 2:.2f}× its variance)")
    lines.append("errors are the bakes' own estimates (per-texel standard error / value); "
                 "baked in Blender by the omis_bake add-on")
    table = "\n".join(lines)
    log(table)
    with open(os.path.join(out, "table.txt"), "w") as f:
        f.write(table.lstrip() + "\n")
    log(f"\nwrote {out}/: balance/optimal .exr .png _filmic.png, noise_comparison.png, "
        f"table.txt")


if __name__ == "__main__":
    main()
