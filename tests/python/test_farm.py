"""Bakes on a Dask.distributed cluster and from the command line.

A LocalCluster of two worker processes gives the local bake's bits, also when
a worker is killed mid-bake (its tasks run again elsewhere: seeds are fixed by
texel, so a retried tile gives the same bits). The command line bakes a
snapshot (locally and through --scheduler), a bake job, and a job's tile
ranges put together, each with the bits of omis.bake_uv.
"""
import json
import os
import shutil
import signal
import subprocess
import sys

import numpy as np
import pytest

import omis
from omis import demo
from omis.__main__ import main as cli_main

distributed = pytest.importorskip("distributed")  # Debian's python3-distributed

SIZE = (80, 48)          # 5 × 3 tiles
SETTINGS = dict(samples=8, seed=21, margin=4)


def bits(result):
    return result.value.tobytes() + result.noise.tobytes() + result.mask.tobytes()


@pytest.fixture(scope="module")
def room():
    scene, floor, _ = demo.build_scene(omis)
    scene.set_mesh_name(floor, "Floor")
    return scene, floor


@pytest.fixture(scope="module")
def local_bits(room):
    scene, floor = room
    return bits(omis.bake_uv(scene, floor, *SIZE, **SETTINGS))


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            yield cluster, client


def test_two_workers_give_the_local_bits(room, local_bits, cluster):
    scene, floor = room
    _, client = cluster
    result = omis.bake_uv(scene, floor, *SIZE, client=client, tiles_per_task=2, **SETTINGS)
    assert bits(result) == local_bits
    assert result.stats["tasks"] == 8 and result.stats["covered"] == SIZE[0] * SIZE[1]
    assert result.stats["samples_per_texel"] == SETTINGS["samples"]
    # A noise target works per tile, as locally: texels stop where they stop there.
    noisy = dict(SETTINGS, samples=128, noise_target=0.08)
    here = omis.bake_uv(scene, floor, *SIZE, **noisy)
    farmed = omis.bake_uv(scene, floor, *SIZE, client=client, tiles_per_task=3, **noisy)
    assert here.stats["samples_per_texel"] < 128  # some texels stopped early
    assert bits(farmed) == bits(here)


def test_a_worker_killed_mid_bake_costs_nothing_but_time(room, local_bits, cluster):
    scene, floor = room
    _, client = cluster
    pids = client.run(os.getpid)
    killed = []

    def kill_one_worker(fraction):
        # After the first tasks finish, the other worker still holds a task.
        if not killed and fraction > 0.1:
            pid = sorted(pids.values())[0]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)
        return True

    result = omis.bake_uv(scene, floor, *SIZE, client=client, tiles_per_task=1,
                          progress=kill_one_worker, **SETTINGS)
    assert killed, "the bake ended before a worker could be killed"
    assert bits(result) == local_bits
    client.wait_for_workers(2, timeout=30)  # the nanny restarts it


def omis_cli(*args):
    env = dict(os.environ)
    out = subprocess.run([sys.executable, "-m", "omis", *args], env=env, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stderr


def arrays(path):
    with np.load(path) as a:
        return a["value"].tobytes() + a["noise"].tobytes() + a["mask"].tobytes()


def test_command_line_bakes_a_snapshot(room, local_bits, cluster, tmp_path):
    scene, _ = room
    snapshot = str(tmp_path / "room.omis")
    scene.save(snapshot)
    common = ["--mesh", "Floor", "--width", str(SIZE[0]), "--height", str(SIZE[1]),
              "--samples", "8", "--seed", "21", "--margin", "4"]
    log = omis_cli("bake", snapshot, *common, "--out", str(tmp_path / "here.exr"))
    assert "done" in log
    assert os.path.getsize(tmp_path / "here.exr") > 0
    assert arrays(tmp_path / "here.npz") == local_bits
    address = cluster[0].scheduler_address
    assert cli_main(["bake", snapshot, *common, "--out", str(tmp_path / "farm.exr"),
                     "--scheduler", address]) == 0
    assert arrays(tmp_path / "farm.npz") == local_bits


def write_job(scene, folder):
    scene.save(str(folder / "room.omis"))
    job = {"format": "omis-bake-job", "version": 1, "snapshot": "room.omis",
           "settings": {"samples": 8, "seed": 21, "margin": 4},
           "units": [{"kind": "uv", "object": "Floor", "mesh": "Floor", "width": SIZE[0],
                      "height": SIZE[1], "image": "lightmap", "output": "out/floor.exr"},
                     {"kind": "corner", "object": "Table", "mesh": 6,
                      "attribute": "omis_direct", "output": "out/table.exr"}]}
    path = folder / "job.json"
    path.write_text(json.dumps(job))
    return path, job


def test_command_line_bakes_a_job_and_its_tile_ranges(room, local_bits, cluster, tmp_path):
    scene, floor = room
    path, _ = write_job(scene, tmp_path)
    assert cli_main(["bake", str(path), "--scheduler", cluster[0].scheduler_address]) == 0
    assert arrays(tmp_path / "out/floor.npz") == local_bits
    os.remove(tmp_path / "out/floor.npz")
    omis_cli("bake", str(path))
    assert arrays(tmp_path / "out/floor.npz") == local_bits
    corners = omis.bake_vertices(scene, 6, domain="CORNER", samples=8, seed=21)
    assert arrays(tmp_path / "out/table.npz") == bits(corners)
    # A farm's tasks (in this process: the command line's own entry point).
    os.remove(tmp_path / "out/floor.npz")
    for first, count in ((0, 6), (6, 6), (12, 3)):  # 15 tiles, 6 a part
        assert cli_main(["bake", str(path), "--unit", "0", "--tiles", f"{first}:{count}"]) == 0
    assert cli_main(["compose", str(path), "--unit", "0", "--tiles-per-part", "6"]) == 0
    assert arrays(tmp_path / "out/floor.npz") == local_bits
    assert cli_main(["compose", str(path), "--unit", "0", "--tiles-per-part", "4"]) == 1


def test_command_line_errors_are_one_line(tmp_path):
    bad = tmp_path / "bad.omis"
    bad.write_bytes(b"OMISSNAP" + b"\0" * 4)
    out = subprocess.run([sys.executable, "-m", "omis", "bake", str(bad), "--mesh", "0",
                          "--width", "8", "--height", "8", "--out", str(tmp_path / "x.exr")],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 1 and "truncated" in out.stderr
    assert "Traceback" not in out.stderr


@pytest.mark.skipif(shutil.which("node") is None, reason="node runs the Flamenco job type")
def test_flamenco_tasks_bake_the_local_bits(room, local_bits, tmp_path):
    """The Flamenco job type's tasks, run in an order its dependencies allow
    (the ranges backwards), give the local bake's bits."""
    scene, _ = room
    path, job = write_job(scene, tmp_path)
    units = [{k: u[k] for k in ("kind", "object", "width", "height") if k in u}
             for u in job["units"]]
    submission = {"name": "room", "settings": {"job_file": str(path), "units": json.dumps(units),
                                               "tiles_per_task": 4, "python": sys.executable}}
    (tmp_path / "submission.json").write_text(json.dumps(submission))
    stub = os.path.join(os.path.dirname(__file__), "..", "flamenco", "flamenco_stub.js")
    script = os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "flamenco",
                          "omis_bake.js")
    tasks = json.loads(subprocess.run(["node", stub, script, str(tmp_path / "submission.json")],
                                      capture_output=True, text=True, check=True).stdout)
    assert len(tasks) == 4 + 1 + 1  # 15 tiles in 4 ranges, their compose, the corner unit
    done = set()
    pending = list(reversed(tasks))
    while pending:
        task = next(t for t in pending if set(t["dependencies"]) <= done)
        for command in task["commands"]:
            assert command["parameters"]["exe"] == sys.executable
            assert cli_main(command["parameters"]["args"][2:]) == 0  # after "-m omis"
        done.add(task["name"])
        pending.remove(task)
    assert arrays(tmp_path / "out/floor.npz") == local_bits
