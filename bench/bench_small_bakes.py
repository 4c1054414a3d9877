"""Where the time of a small time-budget bake goes (issue 9, "Small bakes"), on
the equal-time race's scenes (bench_cycles.py), and what it reaches.

    bash scripts/blender_run.sh bench/bench_small_bakes.py [--scenes area,...]
        [--budgets 0.05,0.1] [--reps 7] [--size 64] [--strategy optimal-direct]

Each bake is the race's omis_run (BakeJob: export, run, finish) with its parts
timed apart (wall ms, median over --reps after one warm-up bake):
  export    BakeJob(...) — validation and the Blender → omis export
  commit    the committed scene (the last bake's when unchanged: the race's case)
  native    the native bakes (omis.bake_uv), as Python sees them
  inside    of which the native bakes' own clock (stats["seconds"])
  convert   the results to numpy (run()'s rest)
  write     finish(): composing and writing the pixels, the stats
  total     the whole of it, as the race times it
and what the bake reached: samples per texel and passes (medians).
--cpu times export, commit, convert and write by this thread's CPU time
(they run on it; the machine is shared): convert then includes the waiting
thread's own work during the native bakes.
--budgets -N bakes N samples per texel with no time limit (-1: the fixed
cost and one round). --after-cycles N runs a Cycles bake of N samples before
each, as the race does (its depsgraph updates drop mesh_cache's kept reads).
The race itself bakes 128² (bench_cycles.py --size).
"""

import os
import statistics
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
sys.path.insert(0, os.path.join(ROOT, "bench"))
import omis_test_utils as U  # noqa: E402
import cycles_scenes  # noqa: E402

from omis_bake import job as job_module  # noqa: E402
from omis_bake.job import BakeJob  # noqa: E402
from omis_bake.settings import settings_from  # noqa: E402

SCENES = dict(cycles_scenes.SCENES, demo_room=U.demo_room)
CPU = "--cpu" in U.args()
PARTS = ("export", "commit", "native", "inside", "convert", "write", "total")


class NativeTimer:
    """Wraps omis.bake_uv / bake_vertices to time the native calls."""

    def __init__(self, omis):
        self.omis = omis
        self.seconds = 0.0
        self.inside = 0.0

    def __getattr__(self, name):
        attr = getattr(self.omis, name)
        if name not in ("bake_uv", "bake_vertices"):
            return attr

        def timed(*args, **kwargs):
            t = time.perf_counter()
            result = attr(*args, **kwargs)
            self.seconds += time.perf_counter() - t
            self.inside += float(result.stats["seconds"])
            return result
        return timed


def one_bake(objects, image, strategy, budget, seed, cycles_spp=0):
    if cycles_spp:  # as in the race: Cycles' bake of the same budget comes first
        U.set_pixels(image, (0.0, 0.0, 0.0, 0.0))
        U.cycles_bake(objects, cycles_spp, seed)
    U.set_pixels(image, (0.0, 0.0, 0.0, 0.0))
    U.select_only(objects)
    # A budget below 0 bakes -budget samples per texel with no time limit.
    samples, seconds = (int(-budget), 0.0) if budget < 0 else (1 << 30, float(budget))
    overrides = {"samples": samples, "time_budget": seconds, "margin": 0,
                 "seed": int(seed), "use_noise_target": False, "technique_mode": 'AUTO',
                 "use_clear": True}
    if strategy == "balance":
        overrides.update(use_optimal_mis=False, heuristic='BALANCE')
    else:
        overrides.update(use_optimal_mis=True, optimal_mode='DIRECT')
    settings = settings_from(bpy.context.scene.omis, overrides)
    clock = time.thread_time if CPU else time.perf_counter
    w0, c0 = time.perf_counter(), clock()
    job = BakeJob(bpy.context, objects, settings)
    c1 = clock()
    job.export.scene.committed()    # what run() calls first (reused there)
    c2 = clock()
    timer = NativeTimer(job.omis)
    job.omis = timer
    w2 = time.perf_counter()
    job.run()
    w3, c3 = time.perf_counter(), clock()
    stats = job.finish(bpy.context)
    w4, c4 = time.perf_counter(), clock()
    if job.error:
        raise RuntimeError(job.error)
    native = timer.seconds
    return {"export": c1 - c0, "commit": c2 - c1, "native": native, "inside": timer.inside,
            "convert": (w3 - w2) - native if not CPU else c3 - c2, "write": c4 - c3,
            "total": w4 - w0, "spp": stats["samples_per_texel"], "passes": stats["passes"]}


def main():
    args = U.args()

    def opt(name, default):
        return args[args.index(name) + 1] if name in args else default
    scenes = opt("--scenes", "area,shared_image,emissive_mesh,demo_room").split(",")
    budgets = [float(b) for b in opt("--budgets", "0.05,0.1").split(",")]
    reps = int(opt("--reps", "7"))
    size = int(opt("--size", "64"))
    strategy = opt("--strategy", "optimal-direct")
    cycles_spp = int(opt("--after-cycles", "0"))
    print(f"small bakes ({strategy}, {size}², median of {reps}, ms; "
          f"{'export … write: main-thread CPU' if CPU else 'wall'})")
    print("%-14s %6s" % ("scene", "budget") + "".join("%9s" % p for p in PARTS)
          + "%7s %6s" % ("spp", "passes"))
    for name in scenes:
        U.reset_scene()
        objects = SCENES[name](size)
        bpy.context.view_layer.update()
        (image,) = cycles_scenes.images_of(objects)
        one_bake(objects, image, strategy, budgets[0], 1)   # warm-up, commits the scene
        for budget in budgets:
            runs = [one_bake(objects, image, strategy, budget, 10 + r, cycles_spp)
                    for r in range(reps)]
            med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
            print("%-14s %6.3f" % (name, budget)
                  + "".join("%9.1f" % (1e3 * med[p]) for p in PARTS)
                  + "%7.1f %6.0f" % (med["spp"], med["passes"]), flush=True)


main()
