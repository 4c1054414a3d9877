"""Bake jobs: a scene snapshot and a description of what to bake, run headless.

A job file (JSON, written by the Blender add-on's "Export Bake Job") names a
snapshot (``Scene.save``; a path relative to the job file) and the units to
bake, each one omis mesh into a lightmap or onto its triangle corners:

    {"format": "omis-bake-job", "version": 1,
     "snapshot": "level.omis",
     "settings": {"samples": 256, "seed": 0, "strategy": "optimal-direct",
                  "beta": 2.0, "cutoff": 0.1, "techniques": null,
                  "noise_target": null, "time_budget": null,
                  "margin": 16, "margin_type": "extend"},
     "units": [{"kind": "uv", "object": "Floor", "mesh": 0,
                "width": 512, "height": 512, "image": "Floor lightmap",
                "output": "results/000.exr"},
               {"kind": "corner", "object": "Crate", "mesh": 3,
                "attribute": "omis_direct", "output": "results/001.exr"}]}

Each unit's result goes to its ``output`` (EXR: R, G, B, noise, mask, through
omis' image IO; corners as a count × 1 image) and, beside it, the same arrays
as ``.npz`` (value, noise, mask) for the add-on's "Import Bake Job Results".
A time budget is the whole job's, shared out by the units' texels (as the
add-on shares it). A farm splits a job into tile ranges of one unit
(``run_tile_part``, written as ``.part-<first>-<count>.npz``) and puts them
together afterwards (``compose_unit``); the bits are those of a whole bake.
"""
import json
import os
import sys
import time

import numpy as np

from . import _omis, farm

FORMAT = "omis-bake-job"
VERSION = 1
SETTINGS = ("samples", "seed", "strategy", "beta", "cutoff", "techniques", "counts",
            "noise_target", "time_budget")


class JobError(ValueError):
    """A job file that cannot be baked: the message names the problem."""


def load_job(path):
    """The job as a dict, checked; relative paths made absolute (beside the file)."""
    try:
        with open(path, encoding="utf-8") as f:
            job = json.load(f)
    except (OSError, json.JSONDecodeError) as exc:
        raise JobError(f"{path}: cannot read the job ({exc})") from None
    if not isinstance(job, dict) or job.get("format") != FORMAT:
        raise JobError(f"{path}: not an omis bake job (format must be '{FORMAT}')")
    if job.get("version") != VERSION:
        raise JobError(f"{path}: job version {job.get('version')} is not supported "
                       f"(this omis reads version {VERSION})")
    base = os.path.dirname(os.path.abspath(path))
    job["snapshot"] = os.path.join(base, _text(job, "snapshot", path))
    units = job.get("units")
    if not isinstance(units, list) or not units:
        raise JobError(f"{path}: 'units' must be a non-empty list")
    for k, unit in enumerate(units):
        where = f"{path}: unit {k}"
        if unit.get("kind") not in ("uv", "corner"):
            raise JobError(f"{where}: kind must be 'uv' or 'corner'")
        if not isinstance(unit.get("mesh"), (int, str)):
            raise JobError(f"{where}: mesh must be an id or a name")
        if unit["kind"] == "uv":
            for key in ("width", "height"):
                if not isinstance(unit.get(key), int) or unit[key] < 1:
                    raise JobError(f"{where}: {key} must be a positive integer")
        unit["output"] = os.path.join(base, _text(unit, "output", where))
    job.setdefault("settings", {})
    return job


def _text(d, key, where):
    value = d.get(key)
    if not isinstance(value, str) or not value:
        raise JobError(f"{where}: '{key}' must be a non-empty string")
    return value


def resolve_mesh(scene, mesh):
    """A mesh id from an id, a decimal string or a name."""
    if isinstance(mesh, int):
        return mesh
    if isinstance(mesh, str) and mesh.isdigit():
        return int(mesh)
    return scene.find_mesh(mesh)


def bake_options(settings):
    """bake_uv / bake_vertices keyword arguments from a job's settings."""
    return {k: settings[k] for k in SETTINGS if settings.get(k) is not None}


def unit_weight(unit):
    """What a unit costs, for sharing a time budget: its texels (a corner unit,
    whose size the job does not state, as a 64² map)."""
    if unit["kind"] == "uv":
        return unit["width"] * unit["height"]
    return 64 * 64


def write_result(path, result):
    """The unit's EXR (omis' image IO, atomic) and its arrays beside it (.npz)."""
    folder = os.path.dirname(path)
    if folder:
        os.makedirs(folder, exist_ok=True)
    result.write_exr(path)
    save_arrays(os.path.splitext(path)[0] + ".npz", result.value, result.noise, result.mask)


def save_arrays(path, value, noise, mask, **extra):
    tmp = path + f".{os.getpid()}.tmp.npz"
    np.savez(tmp, value=value, noise=noise, mask=mask, **extra)
    os.replace(tmp, path)


class TerminalProgress:
    """Progress on the terminal: one updated line on a TTY, else a line per 10 %."""

    def __init__(self, label, stream=sys.stderr):
        self.label, self.stream = label, stream
        self.tty = stream.isatty()
        self.started = time.monotonic()
        self.last_tenth = -1

    def __call__(self, fraction):
        seconds = time.monotonic() - self.started
        text = f"{self.label}: {100 * fraction:5.1f} %  {seconds:6.1f} s"
        if self.tty:
            self.stream.write("\r" + text)
            self.stream.flush()
        elif int(10 * fraction) > self.last_tenth:
            self.last_tenth = int(10 * fraction)
            self.stream.write(text + "\n")
        return True

    def done(self, stats):
        end = "\n" if self.tty else ""
        self.stream.write(f"{end}{self.label}: done in {time.monotonic() - self.started:.1f} s, "
                          f"{stats.get('samples_per_texel', 0):.0f} samples per texel, "
                          f"mean relative error {stats.get('mean_relative_error', 0):.4f}\n")
        self.stream.flush()


def bake_unit(scene, unit, options, client=None, progress=None):
    """One unit's BakeResult (or DistributedBakeResult with a client)."""
    mesh = resolve_mesh(scene, unit["mesh"])
    if unit["kind"] == "uv":
        return farm_or_local(scene, mesh, unit["width"], unit["height"], options, client,
                             progress)
    if client is not None:
        raise JobError("corner (colour attribute) units bake locally only")
    return _omis.bake_vertices(scene, mesh, domain="CORNER", progress=progress, **options)


def farm_or_local(scene, mesh, width, height, options, client, progress):
    from . import bake_uv

    return bake_uv(scene, mesh, width, height, client=client, progress=progress, **options)


def _unit_options(settings, options, unit):
    out = dict(options)
    if unit["kind"] == "uv":
        out["margin"] = settings.get("margin", 16)
        out["margin_type"] = settings.get("margin_type", "extend")
    return out


def _label(unit, n, total):
    name = unit.get("image") or unit.get("attribute") or ""
    return f"[{n + 1}/{total}] {unit.get('object', unit['mesh'])} → {name}"


def run_job(path, client=None, stream=sys.stderr, units=None):
    """Bakes every unit of a job (or those listed) and writes their outputs.
    With a client, the lightmaps' tiles go to the cluster all at once
    (farm.bake_uv_many); colour attributes bake here."""
    job = load_job(path)
    scene = _omis.Scene.load(job["snapshot"])
    settings = job["settings"]
    options = bake_options(settings)
    chosen = list(range(len(job["units"])) if units is None else units)
    here = [k for k in chosen if client is None or job["units"][k]["kind"] != "uv"]
    farmed = [k for k in chosen if k not in here]
    weights = {k: unit_weight(job["units"][k]) for k in chosen}
    budget = options.pop("time_budget", None)
    started = time.monotonic()
    for n, k in enumerate(here):
        unit = job["units"][k]
        unit_options = _unit_options(settings, options, unit)
        if budget is not None:  # the whole job's: shared out by the units' weights
            left = float(budget) - (time.monotonic() - started)
            share = weights[k] / sum(weights[j] for j in chosen[chosen.index(k):])
            unit_options["time_budget"] = max(1e-3, left * share)
        progress = TerminalProgress(_label(unit, n, len(chosen)), stream)
        result = bake_unit(scene, unit, unit_options, None, progress)
        write_result(unit["output"], result)
        progress.done(result.stats)
    if farmed:
        _run_on_cluster(job, scene, farmed, options, budget, started, client, stream)
    return job


def _run_on_cluster(job, scene, farmed, options, budget, started, client, stream):
    settings = job["settings"]
    units = [job["units"][k] for k in farmed]
    uv_options = _unit_options(settings, options, units[0])
    if budget is not None:
        uv_options["time_budget"] = max(1e-3, float(budget) - (time.monotonic() - started))
    bakes = [(resolve_mesh(scene, u["mesh"]), u["width"], u["height"]) for u in units]
    progress = TerminalProgress(f"{len(units)} lightmaps on {client.scheduler.address}", stream)
    results = farm.bake_uv_many(client, scene, bakes, progress=progress, **uv_options)
    for unit, result in zip(units, results):
        write_result(unit["output"], result)
    progress.done({"samples_per_texel": sum(r.stats["samples"] for r in results) /
                   max(1, sum(r.stats["covered"] for r in results)),
                   "mean_relative_error": float(np.mean([r.stats["mean_relative_error"]
                                                         for r in results]))})


# ---- Tile ranges of one unit (a farm's tasks) ----------------------------------

def part_path(unit, first, count):
    return os.path.splitext(unit["output"])[0] + f".part-{first}-{count}.npz"


def run_tile_part(path, unit_index, first, count, stream=sys.stderr):
    """Bakes tiles [first, first + count) of a lightmap unit into its part file."""
    job = load_job(path)
    unit = _unit(job, unit_index, "uv")
    scene = _omis.Scene.load(job["snapshot"])
    settings = job["settings"]
    options = bake_options(settings)
    options.pop("time_budget", None)  # a farm's tasks bake to samples or noise
    progress = TerminalProgress(f"unit {unit_index} tiles {first}+{count}", stream)
    result = _omis.bake_uv(scene, resolve_mesh(scene, unit["mesh"]), unit["width"],
                           unit["height"], first_tile=first, tile_count=count,
                           margin=settings.get("margin", 16), progress=progress, **options)
    out = part_path(unit, first, count)
    os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
    save_arrays(out, result.value, result.noise, result.mask)
    progress.done(result.stats)
    return out


def compose_unit(path, unit_index, tiles_per_part, stream=sys.stderr):
    """Puts a lightmap unit's part files together (margin filled) into its outputs."""
    job = load_job(path)
    unit = _unit(job, unit_index, "uv")
    scene = _omis.Scene.load(job["snapshot"])
    width, height = unit["width"], unit["height"]
    tiles = _omis.bake_tile_count(width, height)
    value = np.zeros((height, width, 3), np.float32)
    noise = np.zeros((height, width), np.float32)
    mask = np.zeros((height, width), np.float32)
    for first, count in farm.fixed_ranges(tiles, tiles_per_part):
        part = part_path(unit, first, count)
        if not os.path.isfile(part):
            raise JobError(f"unit {unit_index}: the part {part} is missing (tiles {first}+{count})")
        with np.load(part) as arrays:
            baked = arrays["mask"] > 0
            value[baked] = arrays["value"][baked]
            noise[baked] = arrays["noise"][baked]
            mask[baked] = 1.0
    settings = job["settings"]
    result = _omis.compose_bake_uv(scene, resolve_mesh(scene, unit["mesh"]), width, height,
                                   value, noise, mask, margin=settings.get("margin", 16),
                                   margin_type=settings.get("margin_type", "extend"))
    write_result(unit["output"], result)
    stream.write(f"unit {unit_index}: composed {unit['output']}\n")
    return unit["output"]


def _unit(job, index, kind):
    if not 0 <= index < len(job["units"]):
        raise JobError(f"unit {index}: the job has {len(job['units'])} units")
    unit = job["units"][index]
    if unit["kind"] != kind:
        raise JobError(f"unit {index}: a {unit['kind']} unit has no tiles")
    return unit
