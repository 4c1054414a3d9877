"""Bake jobs for a farm: export a scene snapshot and a job file, import the results.

    export_bake_job(context, "/shared/level/job.json")        # snapshot + job JSON
    python3 -m omis bake /shared/level/job.json [--scheduler tcp://...]   (anywhere)
    import_bake_job_results(context, "/shared/level/job.json") # into images, attributes

The job file is omis' (``omis.job``: snapshot, settings, units with their
outputs); the add-on adds a ``blender`` section (the objects and settings) so
that the import finds the same images and colour attributes again: it exports
the scene anew, checks that it still yields the units the job baked, and
writes the results through the bake's own write-back (nothing is written
unless every unit's result is there and fits). ``units.json`` beside the job
holds the units as the Flamenco job type takes them.
"""

import json
import os

import numpy as np

from .errors import BakeError
from .job import MARGIN_TYPES, BakeJob
from .settings import ARGUMENT_NAMES, settings_from

SNAPSHOT = "scene.omis"


def _write_json(path, data):
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1)
    os.replace(tmp, path)


def _unit_record(k, unit):
    record = {"kind": unit.kind, "object": unit.part.object_name, "mesh": unit.part.mesh_id,
              "output": f"results/{k:03d}.exr"}
    if unit.kind == 'uv':
        record.update(width=unit.target.width, height=unit.target.height, image=unit.target.name)
    else:
        record.update(attribute=unit.target.attribute_name)
    return record


def _omis_settings(s):
    return {"samples": int(s.samples), "seed": int(s.seed), "strategy": s.strategy,
            "beta": float(s.power_beta), "cutoff": float(s.cutoff_threshold),
            "techniques": s.technique_names(),
            "noise_target": float(s.noise_target) if s.use_noise_target else None,
            "time_budget": float(s.time_budget) if s.time_budget > 0 else None,
            "margin": int(s.margin), "margin_type": MARGIN_TYPES[s.margin_type]}


def _blender_settings(s):
    out = {}
    for name in ARGUMENT_NAMES:
        if hasattr(s, name):
            value = getattr(s, name)
            out[name] = sorted(value) if name == "techniques" else value
    return out


def export_bake_job(context, path, objects=None, **overrides):
    """Writes the snapshot and the job for `objects` (default: the selected
    ones) with scene.omis' settings (and overrides); returns the job dict."""
    s = settings_from(context.scene.omis, overrides)
    job = BakeJob(context, objects, s)
    scene = job.export.scene.committed()
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    units = []
    for k, unit in enumerate(job.units):
        scene.set_mesh_name(unit.part.mesh_id, unit.part.object_name)
        units.append(_unit_record(k, unit))
    scene.save(os.path.join(folder, SNAPSHOT))
    data = {"format": "omis-bake-job", "version": 1, "snapshot": SNAPSHOT,
            "settings": _omis_settings(s), "units": units,
            "blender": {"objects": list(job.object_names), "settings": _blender_settings(s)}}
    _write_json(path, data)
    flamenco = [{k: u[k] for k in ("kind", "object", "width", "height") if k in u} for u in units]
    _write_json(os.path.join(folder, "units.json"), flamenco)
    return data


def _read_result(folder, record):
    path = os.path.splitext(os.path.join(folder, record["output"]))[0] + ".npz"
    if not os.path.isfile(path):
        raise BakeError(f'no result for {record["object"]} yet ({path}): bake the job first')
    with np.load(path) as a:
        return (np.array(a["value"], np.float32), np.array(a["noise"], np.float32),
                np.array(a["mask"], np.float32))


def _check_same_units(job, records):
    baked = [(r["kind"], r["object"], r["mesh"], r.get("width"), r.get("height")) for r in records]
    now = [(u.kind, u.part.object_name, u.part.mesh_id,
            u.target.width if u.kind == 'uv' else None,
            u.target.height if u.kind == 'uv' else None) for u in job.units]
    if baked != now:
        raise BakeError("the scene no longer matches the bake job (objects, meshes, images or "
                        "sizes changed since Export Bake Job): export and bake it again")


def _result_stats(value, noise, mask):
    covered = int(np.count_nonzero(mask > 0))
    errors = noise[mask > 0] if covered else np.zeros(0, np.float32)
    return {"status": "complete", "seconds": 0.0, "covered": covered, "samples": 0,
            "mean_relative_error": float(errors.mean()) if errors.size else 0.0,
            "max_relative_error": float(errors.max()) if errors.size else 0.0, "plan": ""}


def import_bake_job_results(context, path):
    """Writes a baked job's results into its images and colour attributes;
    returns the bake's stats dict. BakeError when anything is missing or the
    scene changed; then nothing is written."""
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
        blender = data["blender"]
        records = data["units"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise BakeError(f"{path}: not a bake job exported by omis Bake ({exc})") from None
    s = settings_from(context.scene.omis, blender["settings"])
    job = BakeJob(context, blender["objects"], s)
    _check_same_units(job, records)
    folder = os.path.dirname(os.path.abspath(path))
    for unit, record in zip(job.units, records):
        unit.value, unit.noise, unit.mask = _read_result(folder, record)
        expected = ((unit.target.height, unit.target.width, 3) if unit.kind == 'uv'
                    else (3 * unit.part.triangles, 3))
        if unit.value.shape != expected:
            raise BakeError(f'{record["object"]}: the result is {unit.value.shape}, '
                            f'expected {expected}')
        unit.stats = _result_stats(unit.value, unit.noise, unit.mask)
    job.done = True
    return job.finish(context)
