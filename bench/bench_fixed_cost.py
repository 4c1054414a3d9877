"""The fixed cost of a bake of the emissive_mesh race scene (issues 8, 9):
export (Python), scene commit (Embree BVHs, triangle lights, emitter shapes),
and the bake's first pass (light tree, tables, one sample per texel), each
timed apart, at several sphere resolutions.

    bash scripts/blender_run.sh bench/bench_fixed_cost.py [--segments 128,316] [--reps 5]

Per resolution: the scene cache is cleared before each repetition so that the
commit is paid (a race's first bake); the fastest repetition of each part is
printed: the process's CPU time over all threads (the machine is shared), or
wall time with --wall. `reused` times a second bake
of the unchanged scene (export, the cache's comparison, first pass).
"""

import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
import omis_test_utils as U  # noqa: E402
import cycles_scenes  # noqa: E402

from omis_bake import scene_cache  # noqa: E402
from omis_bake.job import BakeJob  # noqa: E402
from omis_bake.settings import settings_from  # noqa: E402


def build(segments):
    U.reset_scene()
    img = U.make_image("bake", cycles_scenes.SIZE)
    objs = [cycles_scenes.receiver(img, size=2.0, cuts=2)]
    bpy.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=segments // 2,
                                         radius=0.3, location=(0.2, 0.1, 0.6))
    sphere = bpy.context.active_object
    sphere.data.materials.append(U.emission_material("Glow", (1.0, 0.85, 0.7), 3.0))
    U.add_light('AREA', "square", energy=40.0, location=(0.35, 0.2, 1.4), shape='SQUARE',
                size=0.3)
    bpy.context.view_layer.update()
    return objs, len(sphere.data.polygons)


def one_bake(objs):
    U.select_only(objs)
    overrides = {"samples": 1, "time_budget": 0.0, "margin": 0, "seed": 1,
                 "use_noise_target": False, "technique_mode": 'AUTO', "use_clear": True,
                 "use_optimal_mis": False, "heuristic": 'BALANCE'}
    settings = settings_from(bpy.context.scene.omis, overrides)
    marks = [(time.perf_counter(), time.process_time())]
    job = BakeJob(bpy.context, objs, settings)
    marks.append((time.perf_counter(), time.process_time()))
    job.export.scene.committed()
    marks.append((time.perf_counter(), time.process_time()))
    job.run()          # the committed scene is reused: the first pass alone
    marks.append((time.perf_counter(), time.process_time()))
    job.finish(bpy.context)
    marks.append((time.perf_counter(), time.process_time()))
    clock = 1 if CPU else 0
    t = [m[clock] for m in marks]
    return {"export": t[1] - t[0], "commit": t[2] - t[1], "first pass": t[3] - t[2],
            "write-back": t[4] - t[3], "total": t[4] - t[0]}


CPU = "--wall" not in U.args()


def main():
    args = U.args()
    segments = [int(s) for s in (args[args.index("--segments") + 1].split(",")
                                 if "--segments" in args else ["128", "316"])]
    reps = int(args[args.index("--reps") + 1]) if "--reps" in args else 5
    parts = ("export", "commit", "first pass", "write-back", "total")
    print("fixed cost of an emissive_mesh bake, best of %d (%s ms)" % (reps, "CPU" if CPU else "wall"))
    print("%9s %9s" % ("segments", "triangles") + "".join("%12s" % p for p in parts)
          + "%12s" % "reused")
    for seg in segments:
        objs, quads = build(seg)
        best = {p: 1e300 for p in parts}
        reused = 1e300
        for _ in range(reps):
            scene_cache.clear()
            t = one_bake(objs)
            for p in parts:
                best[p] = min(best[p], t[p])
            reused = min(reused, one_bake(objs)["total"])
        triangles = 2 * seg * (seg // 2 - 1)
        print("%9d %9d" % (seg, triangles) + "".join("%12.1f" % (1e3 * best[p]) for p in parts)
              + "%12.1f" % (1e3 * reused), flush=True)


main()
