"""The omis command line: bake scene snapshots and bake jobs headless.

    python3 -m omis bake SNAPSHOT --mesh ID_OR_NAME --width W --height H
        --samples N --seed S --out FILE.exr [--scheduler ADDRESS]
    python3 -m omis bake JOB.json [--scheduler ADDRESS]
    python3 -m omis bake JOB.json --unit K --tiles FIRST:COUNT     (a farm's task)
    python3 -m omis compose JOB.json --unit K --tiles-per-part N   (after the tasks)

--scheduler bakes the lightmaps' tiles as tasks on a Dask.distributed cluster
(``dask-scheduler`` / ``dask-worker``, or any scheduler address), with Dask's
progress on the terminal and its dashboard; the results have the bits of a
local bake. Progress goes to stderr; exit status 0 on success, 1 on an error
(message on stderr), 2 on bad arguments.
"""
import argparse
import sys

from . import _omis, job

SNAPSHOT_MAGIC = b"OMISSNAP"


def parser():
    p = argparse.ArgumentParser(prog="python3 -m omis", description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    b = sub.add_parser("bake", help="bake a snapshot's mesh, or every unit of a bake job")
    b.add_argument("target", help="a scene snapshot (Scene.save) or a bake job (.json)")
    b.add_argument("--mesh", help="snapshot: the mesh's id or name")
    b.add_argument("--width", type=int, help="snapshot: lightmap width")
    b.add_argument("--height", type=int, help="snapshot: lightmap height")
    b.add_argument("--samples", type=int, default=64, help="samples per texel (64)")
    b.add_argument("--seed", type=int, default=0, help="random seed (0)")
    b.add_argument("--strategy", default="optimal-direct", help="MIS strategy (optimal-direct)")
    b.add_argument("--techniques", help="comma-separated technique names (the plan's default)")
    b.add_argument("--time-budget", type=float, help="seconds for the whole bake")
    b.add_argument("--noise-target", type=float, help="relative standard error per texel")
    b.add_argument("--margin", type=int, default=16, help="texels around UV islands (16)")
    b.add_argument("--margin-type", default="extend", choices=("extend", "adjacent-faces"))
    b.add_argument("--threads", type=int, default=0, help="threads (0 = all cores)")
    b.add_argument("--out", help="snapshot: the EXR to write (R, G, B, noise, mask)")
    b.add_argument("--scheduler", help="a Dask.distributed scheduler address (tcp://host:8786)")
    b.add_argument("--tiles-per-task", type=int, help="with --scheduler: tiles per Dask task")
    b.add_argument("--unit", type=int, help="job: bake only this unit")
    b.add_argument("--tiles", help="job, with --unit: only tiles FIRST:COUNT, into a part file")
    c = sub.add_parser("compose", help="put a job unit's tile parts together")
    c.add_argument("job")
    c.add_argument("--unit", type=int, required=True)
    c.add_argument("--tiles-per-part", type=int, required=True)
    return p


def is_snapshot(path):
    try:
        with open(path, "rb") as f:
            return f.read(8) == SNAPSHOT_MAGIC
    except OSError as exc:
        raise job.JobError(f"{path}: cannot read ({exc.strerror})") from None


def connect(address):
    if address is None:
        return None
    from distributed import Client

    client = Client(address)
    sys.stderr.write(f"omis: Dask scheduler {address}, dashboard {client.dashboard_link}\n")
    return client


def bake_snapshot(args, client):
    for name in ("mesh", "width", "height", "out"):
        if getattr(args, name) is None:
            raise SystemExit(f"python3 -m omis bake: a snapshot needs --{name}")
    scene = _omis.Scene.load(args.target)
    mesh = job.resolve_mesh(scene, args.mesh)
    options = dict(samples=args.samples, seed=args.seed, strategy=args.strategy,
                   margin=args.margin, margin_type=args.margin_type,
                   time_budget=args.time_budget, noise_target=args.noise_target)
    if args.techniques:
        options["techniques"] = args.techniques
    if client is None:
        options["threads"] = args.threads
    else:
        options["tiles_per_task"] = args.tiles_per_task
    progress = job.TerminalProgress(f"{args.target} mesh {args.mesh} {args.width}×{args.height}")
    from . import bake_uv

    result = bake_uv(scene, mesh, args.width, args.height, client=client, progress=progress,
                     **options)
    job.write_result(args.out, result)
    progress.done(result.stats)


def bake_job(args, client):
    if args.tiles is not None:
        if args.unit is None:
            raise SystemExit("python3 -m omis bake: --tiles needs --unit")
        first, _, count = args.tiles.partition(":")
        if not (first.isdigit() and count.isdigit()):
            raise SystemExit("python3 -m omis bake: --tiles takes FIRST:COUNT")
        job.run_tile_part(args.target, args.unit, int(first), int(count))
        return
    job.run_job(args.target, client=client, units=None if args.unit is None else [args.unit])


def main(argv=None):
    args = parser().parse_args(argv)
    try:
        if args.command == "compose":
            job.compose_unit(args.job, args.unit, args.tiles_per_part)
            return 0
        client = connect(args.scheduler)
        try:
            if is_snapshot(args.target):
                bake_snapshot(args, client)
            else:
                bake_job(args, client)
        finally:
            if client is not None:
                client.close()
    except (ValueError, RuntimeError, OSError, _omis.Cancelled) as exc:
        sys.stderr.write(f"omis: {exc}\n")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
