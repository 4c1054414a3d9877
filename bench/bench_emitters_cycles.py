"""Emitter scaling against Cycles' own bake: time per texel-sample of omis and of
Cycles on the same scenes, in one run.

    bash scripts/blender_run.sh bench/bench_emitters_cycles.py [--families sphere,panel,point,area]
        [--max-emitters N] [--size N]

Scenes (as bench/bench_emitters.cpp): a floor of 4 m with a size² float image,
and an emissive UV sphere (radius 0.5 m at 1.5 m, 16 to ~100k triangles; from
64 triangles omis draws it as one mesh light, Scene::set_mesh_lights), an
emissive panel (a 1 m square at 1.5 m, subdivided into 2 to ~100k triangles:
flat, so each triangle stays a light of omis' light tree), or a grid over
[−2, 2]² at 1 m of point lights or of 5 cm area lights facing down (1 to 10k),
total power fixed.

Per scene and renderer, the operator's time is fitted as t0 + k·spp from two
bakes (Cycles: 2 and 32 spp; omis: 4 and 64 samples per texel, the effect
plan's techniques, balance heuristic); k / texels is the time per
texel-sample, in elapsed time and in the process's CPU time (all threads);
growth is each renderer's CPU per sample over its own at the family's fewest
emitters (issue 8's target: omis at most 2x from 16 to ~100k). Cycles' Diffuse
bake, DIRECT only, margin 0; omis through the add-on's BakeJob (both timed as
in bench/bench_cycles.py).
"""

import argparse
import math
import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
import omis_test_utils as U  # noqa: E402

from omis_bake.job import BakeJob  # noqa: E402
from omis_bake.settings import settings_from  # noqa: E402


log = U.log
script_args = U.args


def floor_scene(size):
    U.reset_scene()
    img = U.make_image("bake", size)
    ob = U.image_grid("Floor", img, material="FloorMat", size=4.0, cuts=1)
    return [ob]


def sphere(stacks, slices):
    def build():
        bpy.ops.mesh.primitive_uv_sphere_add(segments=slices, ring_count=stacks, radius=0.5,
                                             location=(0, 0, 1.5))
        bpy.context.active_object.data.materials.append(U.emission_material("Glow"))
    return build


def panel(cuts):
    def build():
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=cuts, y_subdivisions=cuts, size=1.0,
                                        location=(0, 0, 1.5))
        bpy.context.active_object.data.materials.append(U.emission_material("Glow"))
    return build


def grid(kind, side):
    def build():
        for j in range(side):
            for i in range(side):
                x = 0.0 if side == 1 else -2 + 4.0 * i / (side - 1)
                y = 0.0 if side == 1 else -2 + 4.0 * j / (side - 1)
                if kind == "point":
                    U.add_light('POINT', f"p{i}_{j}", energy=500.0 / side ** 2,
                                location=(x, y, 1.0), shadow_soft_size=0.0)
                else:
                    U.add_light('AREA', f"a{i}_{j}", energy=500.0 / side ** 2,
                                location=(x, y, 1.0), shape='SQUARE', size=0.05)
    return build


def per_sample(run, lo, hi):
    """(wall, CPU) seconds per texel-sample from two runs; run(n) -> (wall, CPU,
    samples per texel). CPU is the Blender process's time over all its threads:
    on the shared machine, waiting for a core is no renderer's cost."""
    run(1)  # warm-up
    (w_lo, c_lo, s_lo), (w_hi, c_hi, s_hi) = run(lo), run(hi)
    ds = max(s_hi - s_lo, 1e-9)
    return max((w_hi - w_lo) / ds, 1e-12), max((c_hi - c_lo) / ds, 1e-12)


def cycles(objects):
    def run(spp):
        cpu = time.process_time()
        wall = U.cycles_bake(objects, spp, 7)
        return wall, time.process_time() - cpu, spp
    return run


def omis(objects):
    """The add-on's whole bake (export, native bake, write-back), as bench_cycles.py."""
    def run(n):
        U.select_only(objects)
        overrides = {"samples": int(n), "time_budget": 0.0, "margin": 0, "seed": 7,
                     "use_noise_target": False, "technique_mode": 'AUTO', "use_clear": True,
                     "use_optimal_mis": False, "heuristic": 'BALANCE'}
        start, cpu = time.perf_counter(), time.process_time()
        job = BakeJob(bpy.context, objects, settings_from(bpy.context.scene.omis, overrides))
        job.run()
        stats = job.finish(bpy.context)
        # Delta-only scenes draw no MIS samples: count the requested ones.
        return (time.perf_counter() - start, time.process_time() - cpu,
                stats["samples_per_texel"] or n)
    return run


def main():
    argv = script_args()
    parser = argparse.ArgumentParser()
    parser.add_argument("--families", default="sphere,panel,point,area")
    parser.add_argument("--max-emitters", type=int, default=100000)
    parser.add_argument("--size", type=int, default=64)
    args = parser.parse_args(argv)
    families = args.families.split(",")
    scenes = []
    if "sphere" in families:
        for stacks, slices in ((2, 8), (8, 16), (20, 40), (64, 128), (158, 316)):
            scenes.append(("emissive sphere", 2 * slices * (stacks - 1), sphere(stacks, slices)))
    if "panel" in families:
        # Blender 3.4's grid of c subdivisions has c² quads.
        for cuts in (1, 3, 10, 90, 224):
            scenes.append(("emissive panel", 2 * cuts * cuts, panel(cuts)))
    for kind in ("point", "area"):
        if kind in families:
            for side in (1, 4, 16, 100):
                scenes.append((f"{kind} lights", side * side, grid(kind, side)))
    texels = args.size * args.size
    log(f"time per texel-sample (µs), {texels} texels; omis: balance, the plan's techniques")
    log("wall: elapsed; CPU: the process's CPU time over all threads")
    log("growth: CPU per sample over the family's first (fewest emitters) row, each renderer's own")
    log(f"{'scene':<16} {'emitters':>9} {'cycles':>9} {'omis':>9} {'omis/cycles':>12}"
        f" {'cycles CPU':>11} {'omis CPU':>9} {'CPU ratio':>10}"
        f" {'cycles growth':>14} {'omis growth':>12}")
    first_cpu = {}  # family -> (Cycles, omis) CPU per sample of its first row
    for family, emitters, build in scenes:
        if emitters > args.max_emitters:
            continue
        objects = floor_scene(args.size)
        build()
        c, c_cpu = (1e6 * t / texels for t in per_sample(cycles(objects), 2, 32))
        o, o_cpu = (1e6 * t / texels for t in per_sample(omis(objects), 4, 64))
        c_first, o_first = first_cpu.setdefault(family, (c_cpu, o_cpu))
        log(f"{family:<16} {emitters:>9} {c:>9.3f} {o:>9.3f} {o / c:>11.2f}x"
            f" {c_cpu:>11.3f} {o_cpu:>9.3f} {o_cpu / c_cpu:>9.2f}x"
            f" {c_cpu / c_first:>13.2f}x {o_cpu / o_first:>11.2f}x")


if __name__ == "__main__":
    main()
