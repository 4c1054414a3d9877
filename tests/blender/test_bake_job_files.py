"""Bake jobs through files (omis_bake/bake_job_files.py, its operators): Export Bake
Job writes a snapshot and a job; `python3 -m omis bake JOB` bakes it outside
Blender; Import Bake Job Results writes the images and colour attributes with
exactly what the add-on's own bake writes. An import before the bake, or after
the scene changed, writes nothing.

    scripts/blender_run.sh tests/blender/test_bake_job_files.py
"""

import json
import os
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

import omis_bake  # noqa: E402
from omis_bake.errors import BakeError  # noqa: E402

check = U.check
SETTINGS = dict(samples=8, seed=3)


def build():
    U.reset_scene()
    img = U.make_image("floor lightmap", 32)
    floor = U.image_grid("Floor", img, material="FloorMat", size=2.0, cuts=2)
    U.add_light('AREA', "lamp", energy=200.0, location=(0.2, 0.1, 1.2), size=0.6)
    crate = U.add_box("Crate", (0.4, 0.4, 0.3), (0.0, 0.0, 0.3))
    crate.data.color_attributes.new("omis_direct", 'FLOAT_COLOR', 'CORNER')
    return img, floor, crate


def attribute(ob):
    data = ob.data.color_attributes["omis_direct"].data
    out = np.empty(len(data) * 4, np.float32)
    data.foreach_get("color", out)
    return out


def local_bake(img, floor, crate):
    U.select_only([floor])
    omis_bake.bake(bpy.context, target='IMAGE_TEXTURES', **SETTINGS)
    U.select_only([crate])
    omis_bake.bake(bpy.context, target='COLOR_ATTRIBUTES', **SETTINGS)
    return U.pixels(img).copy(), attribute(crate).copy()


# Debian's Python, which Blender embeds (sys.executable may name another one).
PYTHON = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable


def run_cli(job):
    out = subprocess.run([PYTHON, "-m", "omis", "bake", job], capture_output=True,
                         text=True, env=dict(os.environ, PYTHONNOUSERSITE="1"))
    check(out.returncode == 0, f"python3 -m omis bake failed: {out.stderr}")


def main():
    img, floor, crate = build()
    expected_image, expected_attribute = local_bake(img, floor, crate)
    U.set_pixels(img, (0.0, 0.0, 0.0, 1.0))
    folder = U.temp_dir()
    floor_job = os.path.join(folder, "floor", "job.json")
    crate_job = os.path.join(folder, "crate", "job.json")

    U.select_only([floor])
    bake_files = omis_bake.bake_job_files
    data = bake_files.export_bake_job(bpy.context, floor_job, target='IMAGE_TEXTURES', **SETTINGS)
    check([u["object"] for u in data["units"]] == ["Floor"], f"units: {data['units']}")
    units = json.load(open(os.path.join(folder, "floor", "units.json")))
    check(units == [{"kind": "uv", "object": "Floor", "width": 32, "height": 32}], f"{units}")
    U.select_only([crate])
    scene = bpy.context.scene
    scene.render.bake.target = 'VERTEX_COLORS'
    scene.omis.samples, scene.omis.seed = SETTINGS["samples"], SETTINGS["seed"]
    check(bpy.ops.omis.export_bake_job(filepath=crate_job) == {'FINISHED'}, "export operator")
    # An import before the bake writes nothing.
    try:
        bake_files.import_bake_job_results(bpy.context, floor_job)
        check(False, "import before the bake did not fail")
    except BakeError as exc:
        check("bake the job first" in str(exc), str(exc))
    check(np.all(U.pixels(img).reshape(-1, 4)[:, :3] == 0.0), "a failed import changed the image")

    # Out of Blender, then back. Blender's own settings may differ: the job keeps its own.
    bpy.context.scene.omis.samples = 1
    run_cli(floor_job)
    run_cli(crate_job)
    bake_files.import_bake_job_results(bpy.context, floor_job)
    check(np.array_equal(U.pixels(img), expected_image), "imported image differs from the bake")
    check(bpy.ops.omis.import_bake_job_results(filepath=crate_job) == {'FINISHED'}, "operator")
    check(np.array_equal(attribute(crate), expected_attribute),
          "imported colour attribute differs from the bake")

    # After the scene changed (the floor's image smaller), the import refuses.
    img.scale(16, 16)
    U.set_pixels(img, (0.5, 0.5, 0.5, 1.0))
    try:
        bake_files.import_bake_job_results(bpy.context, floor_job)
        check(False, "import into a changed scene did not fail")
    except BakeError as exc:
        check("no longer matches" in str(exc), str(exc))
    check(np.all(U.pixels(img).reshape(-1, 4)[:, :3] == 0.5), "a refused import changed the image")
    print("bake job files: export, command line, import give the add-on's bits")


main()
