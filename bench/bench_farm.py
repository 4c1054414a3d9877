"""A level's lightmaps in one process against a two-worker Dask LocalCluster, the
per-task costs that measures, and a scaling model for 10–100 machines built from them.

    PYTHONPATH=build/python python3 bench/bench_farm.py [--size 128] [--samples 32]
        [--out bench/results/farm_scaling.txt]

The level: a 20 × 12 m hall whose floor is 16 tiles and whose long walls are 8
panels (24 objects with lightmaps), 6 pillars (occluders) and 8 area lamps.
Measured, on this machine (2 cores):
  local    every lightmap by omis.bake_uv in this process (threads = all cores)
  cluster  the same lightmaps by omis.farm.bake_uv_many on a LocalCluster of two
           worker processes × 1 thread (the same 2 cores), at two task sizes;
           the results are checked bit for bit against the local ones
  no-op    Dask's own round trip per task (200 empty tasks)
and the costs the model needs: core-seconds per texel-sample (the tasks' own
clocks, one thread each), overhead per task (wall · slots − task seconds, per
task), the snapshot's size and load time, and the client's compose time per texel.
"""
import argparse
import datetime
import math
import os
import statistics
import subprocess
import sys
import time

import numpy as np

import omis
from omis import demo, farm


def rotate_x(vertices, quarter_turns):
    """Rotation about x by quarter_turns · 90°: +z (the grid's normal) → ∓y."""
    angle = quarter_turns * math.pi / 2
    c, s = round(math.cos(angle)), round(math.sin(angle))
    x, y, z = vertices[:, 0], vertices[:, 1], vertices[:, 2]
    return np.stack([x, c * y - s * z, s * y + c * z], axis=1)


def build_level():
    """(scene, [(mesh id, name)] of the lightmapped objects)."""
    scene = omis.Scene()
    lightmapped = []
    for i in range(4):          # floor: 4 × 4 tiles of 5 × 3 m
        for j in range(4):
            v, t, uv = demo.grid(5.0, 3.0, 6)
            v = v + [-7.5 + 5 * i, -4.5 + 3 * j, 0]
            mesh = scene.add_mesh(v, t, uvs=uv)
            lightmapped.append((mesh, f"floor_{i}{j}"))
    for side, turns in ((6.0, 1), (-6.0, -1)):   # walls: 4 panels a side, facing the hall
        for i in range(4):
            v, t, uv = demo.grid(5.0, 4.0, 6)
            v = rotate_x(v, turns) + [-7.5 + 5 * i, side, 2.0]
            mesh = scene.add_mesh(v, t, uvs=uv)
            lightmapped.append((mesh, f"wall_{'n' if side > 0 else 's'}{i}"))
    for x in (-6.0, 0.0, 6.0):                   # pillars
        for y in (-3.0, 3.0):
            v, t = demo.box((x, y, 2.0), (0.6, 0.6, 4.0))
            scene.add_mesh(v, t)
    for x in (-7.5, -2.5, 2.5, 7.5):             # lamps, facing down
        for y in (-2.0, 2.0):
            scene.add_rect_light((x - 0.5, y - 0.3, 3.8), (0, 0.6, 0), (1.0, 0, 0),
                                 radiance=(30.0, 28.0, 24.0))
    for mesh, name in lightmapped:
        scene.set_mesh_name(mesh, name)
    scene.commit()
    return scene, lightmapped


def noop(x):
    return x


def measure_local(scene, objects, size, samples):
    results, seconds = [], []
    start = time.perf_counter()
    for mesh, _ in objects:
        t = time.perf_counter()
        results.append(omis.bake_uv(scene, mesh, size, size, samples=samples, seed=1))
        seconds.append(time.perf_counter() - t)
    return time.perf_counter() - start, results, seconds


def measure_cluster(client, scene, objects, size, samples, tiles_per_task):
    bakes = [(mesh, size, size) for mesh, _ in objects]
    start = time.perf_counter()
    results = farm.bake_uv_many(client, scene, bakes, samples=samples, seed=1,
                                tiles_per_task=tiles_per_task)
    wall = time.perf_counter() - start
    tasks = sum(r.stats["tasks"] for r in results)
    in_tasks = sum(r.stats["seconds_in_tasks"] for r in results)
    return wall, results, tasks, in_tasks


def noop_round_trip(client, n=200):
    start = time.perf_counter()
    client.gather(client.map(noop, range(n), pure=False))
    return (time.perf_counter() - start) / n


def same_bits(a, b):
    return all(x.value.tobytes() == y.value.tobytes() and x.noise.tobytes() == y.noise.tobytes()
               and x.mask.tobytes() == y.mask.tobytes() for x, y in zip(a, b))


def snapshot_costs(scene, size):
    data = scene.to_bytes()
    loads = []
    for _ in range(3):
        t = time.perf_counter()
        omis.Scene.from_bytes(data)
        loads.append(time.perf_counter() - t)
    z = np.zeros((size, size, 3), np.float32)
    n = np.zeros((size, size), np.float32)
    t = time.perf_counter()
    for _ in range(5):
        omis.compose_bake_uv(scene, 0, size, size, z, n, n)
    compose_per_texel = (time.perf_counter() - t) / 5 / (size * size)
    return len(data), statistics.median(loads), compose_per_texel


# ---- The model --------------------------------------------------------------

# Assumptions that this machine cannot measure (stated in the output):
CORES_PER_MACHINE = 16
NETWORK_BYTES_PER_S = 125e6     # 1 Gbit/s from the client to the workers and back
RESULT_BYTES_PER_TEXEL = 20     # value (3 floats), noise, mask, float32


def model(c, overhead, snapshot_bytes, load_s, compose_per_texel, objects, size, samples,
          tiles_per_task, machines):
    """Predicted wall seconds of a level bake on `machines` machines."""
    texels = objects * size * size
    work = texels * samples * c                                  # core-seconds
    tiles = objects * math.ceil(size / 16) ** 2
    tasks = objects * math.ceil(math.ceil(size / 16) ** 2 / tiles_per_task)
    slots = machines * CORES_PER_MACHINE
    task_seconds = work / tasks + overhead
    waves = math.ceil(tasks / slots)
    scatter = machines * snapshot_bytes / NETWORK_BYTES_PER_S    # broadcast from the client
    results = texels * RESULT_BYTES_PER_TEXEL / NETWORK_BYTES_PER_S
    compose = texels * compose_per_texel
    return {"tasks": tasks, "tiles": tiles, "waves": waves, "work_h": work / 3600,
            "wall": scatter + load_s + waves * task_seconds + results + compose,
            "ideal": work / slots}


def model_table(costs, objects, size, samples, tiles_per_task):
    c, overhead, snapshot_bytes, load_s, compose = costs
    rows = [f"level: {objects} objects at {size}², {samples} samples per texel, "
            f"{tiles_per_task} tiles (of 16²) a task"]
    one = model(*costs, objects, size, samples, tiles_per_task, 1)
    rows.append(f"  work {one['work_h']:.1f} core-hours, {one['tasks']} tasks; "
                f"1 machine: {one['wall'] / 3600:.2f} h")
    rows.append("  machines  wall (min)  speed-up  efficiency  waves")
    for m in (10, 20, 50, 100):
        r = model(*costs, objects, size, samples, tiles_per_task, m)
        speedup = one["wall"] / r["wall"]
        rows.append(f"  {m:8d}  {r['wall'] / 60:10.1f}  {speedup:8.1f}  {speedup / m:10.2f}  "
                    f"{r['waves']:5d}")
    return rows


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--samples", type=int, default=32)
    p.add_argument("--out", default=None)
    args = p.parse_args()
    from distributed import Client, LocalCluster

    scene, objects = build_level()
    lines = []
    say = lambda text="": (print(text, flush=True), lines.append(text))  # noqa: E731
    snapshot_bytes, load_s, compose_per_texel = snapshot_costs(scene, args.size)
    say(f"level: {len(objects)} lightmapped objects ({args.size}², {args.samples} samples per "
        f"texel), 6 pillars, 8 area lamps; snapshot {snapshot_bytes / 1e3:.1f} kB, "
        f"load {1e3 * load_s:.1f} ms, compose {1e9 * compose_per_texel:.1f} ns/texel")
    local_wall, local, per_object = measure_local(scene, objects, args.size, args.samples)
    say(f"local (one process, 2 threads): {local_wall:.2f} s "
        f"({1e3 * statistics.median(per_object):.0f} ms median per object)")

    t = time.perf_counter()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        say(f"cluster start (2 worker processes): {time.perf_counter() - t:.2f} s "
            "(once, not counted)")
        noop_s = noop_round_trip(client)
        say(f"Dask round trip of an empty task: {1e3 * noop_s:.2f} ms")
        runs = []
        for tiles_per_task in (None, 16, 4):
            wall, results, tasks, in_tasks = measure_cluster(client, scene, objects, args.size,
                                                             args.samples, tiles_per_task)
            assert same_bits(results, local), "the cluster's bits differ from the local bake's"
            overhead = (wall * 2 - in_tasks) / tasks
            runs.append((tasks, wall, in_tasks, overhead))
            say(f"cluster, {tasks:4d} tasks: {wall:.2f} s = {wall / local_wall:.2f}× local; "
                f"tasks' own time {in_tasks:.2f} core-s; overhead {1e3 * overhead:.1f} ms a task "
                f"(bits equal to local: yes)")
    # The model's costs: the per-core rate from the tasks' own clocks (one
    # thread each), the overhead of the finest split (the most tasks, the
    # best measure of it); the snapshot and compose as measured above.
    tasks, wall, in_tasks, overhead = max(runs, key=lambda r: r[0])
    texels = sum(int(r.mask.sum()) for r in local)
    c = min(r[2] for r in runs) / (texels * args.samples)
    costs = (c, max(overhead, noop_s), snapshot_bytes, load_s, compose_per_texel)
    say()
    say(f"model inputs: {1e9 * c:.0f} ns per texel-sample per core; {1e3 * costs[1]:.1f} ms "
        f"overhead a task; assumed {CORES_PER_MACHINE} cores a machine, "
        f"{NETWORK_BYTES_PER_S * 8 / 1e9:.0f} Gbit/s to the client, {RESULT_BYTES_PER_TEXEL} B a "
        f"texel back")
    say("model: wall = M·snapshot/bandwidth + load + waves·(work/tasks + overhead) "
        "+ results/bandwidth + compose,  waves = ⌈tasks / (M·cores)⌉")
    for objects_n, size, samples in ((100, 1024, 256), (100, 1024, 1024), (500, 512, 256)):
        for row in model_table(costs, objects_n, size, samples, 64):
            say(row)
    if args.out:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True).stdout.strip()
        header = [f"# bench/bench_farm.py, commit {commit}, "
                  f"{datetime.datetime.utcnow():%Y-%m-%d %H:%M} UTC",
                  f"# command: PYTHONPATH=build/python python3 bench/bench_farm.py "
                  f"--size {args.size} --samples {args.samples} --out {args.out}",
                  "# machine: 2 cores, shared with other work (load average %.1f at the end; "
                  "timings noisy, ratios from one run; the tasks' clocks are wall clocks, so "
                  "on a loaded machine they overstate the per-core cost)" % os.getloadavg()[0]]
        with open(args.out, "w", encoding="utf-8") as f:
            f.write("\n".join(header + lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
