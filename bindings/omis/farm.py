"""Lightmap bakes on many machines, through Dask.distributed.

``omis.bake_uv(scene, mesh, width, height, client=client, ...)`` bakes the
lightmap's 16×16-texel tiles as Dask tasks, each a contiguous range of tiles
(``omis.bake_uv(..., first_tile=, tile_count=)``), and puts the ranges
together on the client (``omis.compose_bake_uv``, which fills the margin as a
whole bake does). Every texel's draws are fixed by its index and the seed, not
by which task or thread shades it, so the result has the local bake's bits,
and a task that is retried (a worker lost mid-bake) gives the same bits again.

The scene reaches each worker once: its snapshot (``Scene.to_bytes``) is
scattered to every worker (broadcast), and each worker process loads it once
and keeps it for the job's later tasks (``_scene_for``).

Budgets: a sample budget and a noise target work per texel and per tile as in
a local bake. A time budget is the whole job's: each task gets the share of it
that its slot of the cluster can spend, ``time_budget · slots / tasks`` (the
tasks run in ``tasks / slots`` waves); results under a time budget depend on
timing, as they do locally.
"""
import hashlib
import math
import time

import numpy as np

from . import _omis

TILE = 16  # texels on a tile's side (omis.bake_tile_count)

# Per worker process: snapshot digest -> loaded Scene. A few jobs' scenes at
# most (a long-lived worker serves job after job).
_scenes = {}
_MOST_SCENES = 4


def _scene_for(digest, snapshot):
    scene = _scenes.get(digest)
    if scene is None:
        if len(_scenes) >= _MOST_SCENES:
            _scenes.pop(next(iter(_scenes)))
        scene = _omis.Scene.from_bytes(snapshot)
        _scenes[digest] = scene
    return scene


def tile_rows(first_tile, tile_count, width, height):
    """The texel rows [y0, y1) that tiles [first_tile, first_tile + tile_count) span."""
    tiles_x = (width + TILE - 1) // TILE
    y0 = first_tile // tiles_x * TILE
    y1 = min(height, ((first_tile + tile_count - 1) // tiles_x + 1) * TILE)
    return y0, y1


def bake_tile_range(digest, snapshot, mesh, width, height, first_tile, tile_count, options):
    """One task: bakes tiles [first_tile, first_tile + tile_count) of the
    lightmap and returns the rows they span (value, noise, mask) and stats."""
    scene = _scene_for(digest, snapshot)
    result = _omis.bake_uv(scene, mesh, width, height, first_tile=first_tile,
                           tile_count=tile_count, **options)
    y0, y1 = tile_rows(first_tile, tile_count, width, height)
    stats = result.stats
    keep = ("status", "seconds", "samples", "rays_traced", "draws", "covered", "passes")
    return {"rows": (y0, y1), "value": result.value[y0:y1].copy(),
            "noise": result.noise[y0:y1].copy(), "mask": result.mask[y0:y1].copy(),
            "stats": {k: stats[k] for k in keep}}


def split_tiles(tiles, tasks):
    """[(first_tile, tile_count)] for `tasks` contiguous ranges of near-equal size."""
    tasks = max(1, min(tiles, tasks))
    bounds = [tiles * k // tasks for k in range(tasks + 1)]
    return [(bounds[k], bounds[k + 1] - bounds[k]) for k in range(tasks)]


def fixed_ranges(tiles, per_range):
    """[(first_tile, tile_count)]: ranges of per_range tiles in order, the last shorter."""
    if per_range < 1:
        raise ValueError("tiles per range: must be at least 1")
    return [(first, min(per_range, tiles - first)) for first in range(0, tiles, per_range)]


def cluster_slots(client):
    """Tasks the cluster runs at once (its workers' threads)."""
    return max(1, sum(client.nthreads().values()))


class DistributedBakeResult:
    """A lightmap baked as Dask tasks: value, noise and mask as BakeResult's
    (row 0 at the bottom), the EXR and PNG writers, and stats summed over the
    tasks (plus tasks, seconds_in_tasks, wall seconds)."""

    def __init__(self, native, stats):
        self._native = native
        self.stats = stats

    value = property(lambda self: self._native.value)
    noise = property(lambda self: self._native.noise)
    mask = property(lambda self: self._native.mask)

    def write_exr(self, path):
        self._native.write_exr(path)

    def write_png(self, path, view="Standard", display="sRGB", exposure=0.0):
        self._native.write_png(path, view, display, exposure)

    def __repr__(self):
        h, w = self.mask.shape
        return f"<omis.farm.DistributedBakeResult {w}×{h} lightmap, {self.stats['tasks']} tasks>"


def _task_options(options, tasks, slots, spent):
    """The options each task bakes with: a whole-job time budget, less the
    `spent` seconds before the tasks start, becomes each task's share; one
    thread per task unless asked (workers run tasks side by side)."""
    per_task = dict(options)
    per_task.setdefault("threads", 1)
    budget = per_task.get("time_budget")
    if budget is not None:
        waves = math.ceil(tasks / slots)
        per_task["time_budget"] = max(1e-3, float(budget) - spent) / waves
    return per_task


def _merge_stats(parts, native, started, tasks):
    """Stats of the whole bake from its tasks'."""
    stats = {"tasks": tasks, "seconds": time.monotonic() - started,
             "seconds_in_tasks": sum(p["stats"]["seconds"] for p in parts)}
    for key in ("samples", "rays_traced", "draws", "covered"):
        stats[key] = sum(p["stats"][key] for p in parts)
    statuses = {p["stats"]["status"] for p in parts}
    stats["status"] = ("time budget reached" if "time budget reached" in statuses
                       else "complete" if "complete" in statuses else statuses.pop())
    covered = stats["covered"]
    mask = native.mask > 0
    noise = native.noise[mask].astype(np.float64)
    stats["texels"] = int(mask.size)
    stats["samples_per_texel"] = stats["samples"] / covered if covered else 0.0
    stats["mean_relative_error"] = float(noise.mean()) if noise.size else 0.0
    stats["max_relative_error"] = float(noise.max()) if noise.size else 0.0
    stats["passes"] = max(p["stats"]["passes"] for p in parts)
    return stats


def _gather_with_progress(client, futures, progress):
    """Waits for the tasks; progress(fraction) after each one (False cancels
    them and raises omis.Cancelled)."""
    from distributed import as_completed

    done = 0
    for _ in as_completed(futures):
        done += 1
        if progress is not None and progress(done / len(futures)) is False:
            client.cancel(futures)
            raise _omis.Cancelled("bake: cancelled")


def _compose(scene, mesh, width, height, parts, options, started, tasks):
    """A DistributedBakeResult from one lightmap's parts (task results)."""
    value = np.zeros((height, width, 3), np.float32)
    noise = np.zeros((height, width), np.float32)
    mask = np.zeros((height, width), np.float32)
    for part in parts:
        y0, y1 = part["rows"]
        baked = part["mask"] > 0
        value[y0:y1][baked] = part["value"][baked]
        noise[y0:y1][baked] = part["noise"][baked]
        mask[y0:y1][baked] = 1.0
    native = _omis.compose_bake_uv(scene, mesh, width, height, value, noise, mask,
                                   margin=options.get("margin", 16),
                                   margin_type=options.get("margin_type", "extend"))
    return DistributedBakeResult(native, _merge_stats(parts, native, started, tasks))


def bake_uv_many(client, scene, bakes, *, tiles_per_task=None, retries=3, progress=None,
                 **options):
    """Several lightmaps of one scene on the cluster at once: bakes is a list of
    (mesh, width, height); returns their DistributedBakeResults in that order.
    All their tasks are queued together (no idle workers between lightmaps)
    and the snapshot is sent once. tiles_per_task: the tasks' size (default:
    about four tasks per cluster slot over all the lightmaps, at least one
    task a lightmap); retries: how often Dask re-runs a task that raised (a
    lost worker's tasks are re-run by the scheduler anyway); a time_budget is
    the whole call's."""
    started = time.monotonic()
    tiles = [_omis.bake_tile_count(w, h) for _, w, h in bakes]
    slots = cluster_slots(client)
    if tiles_per_task is None:
        tiles_per_task = max(1, math.ceil(sum(tiles) / (4 * slots)))
    if tiles_per_task < 1:
        raise ValueError("tiles_per_task: must be at least 1")
    ranges = [split_tiles(n, math.ceil(n / tiles_per_task)) for n in tiles]
    tasks = sum(len(r) for r in ranges)

    snapshot = scene.to_bytes()
    digest = hashlib.sha256(snapshot).hexdigest()
    shared = client.scatter(snapshot, broadcast=True, hash=False)
    per_task = _task_options(options, tasks, slots, time.monotonic() - started)
    futures = [[client.submit(bake_tile_range, digest, shared, mesh, width, height, first, count,
                              per_task, retries=retries, pure=False) for first, count in r]
               for (mesh, width, height), r in zip(bakes, ranges)]
    flat = [f for fs in futures for f in fs]
    try:
        _gather_with_progress(client, flat, progress)
        parts = [client.gather(fs) for fs in futures]
    finally:
        client.cancel(flat + [shared])
    return [_compose(scene, mesh, width, height, p, options, started, len(p))
            for (mesh, width, height), p in zip(bakes, parts)]


def bake_uv_distributed(client, scene, mesh, width, height, **options):
    """omis.bake_uv with client=: bake_uv_many for one lightmap."""
    return bake_uv_many(client, scene, [(mesh, width, height)], **options)[0]
