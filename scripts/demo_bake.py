#!/usr/bin/env python3
"""The main job: bake the built-in demo scene's floor lightmap with the balance
heuristic and with optimal MIS at equal time, write EXR/PNG results and a noise
comparison, and print what accuracy cost.

    PYTHONPATH=build/python python3 scripts/demo_bake.py [--out DIR] [--seconds S] [--size N]
"""
import argparse
import os
import sys
import time

import numpy as np

import omis
import omis.demo


def progress_bar(label):
    """A progress callable for the bake: redraws in place on a terminal, and
    prints every 10 % otherwise (logs)."""
    start = time.monotonic()
    tty = sys.stdout.isatty()
    shown = [-1]

    def show(fraction):
        step = int(fraction * 10)
        if not tty and step == shown[0]:
            return True
        shown[0] = step
        filled = int(30 * fraction)
        sys.stdout.write(f"{chr(13) if tty else ''}  {label:<14} [{'#' * filled}{'.' * (30 - filled)}] "
                         f"{100 * fraction:5.1f}%  {time.monotonic() - start:5.1f}s{'' if tty else chr(10)}")
        sys.stdout.flush()
        if fraction >= 1.0 and tty:
            sys.stdout.write("\n")
        return True

    return show


def noise_comparison(path, maps, labels, stats):
    """Side-by-side maps of the estimated relative error, one shared scale.
    maps: (noise, mask) per bake; stats: the bakes' stats dicts. Shared with
    scripts/blender_demo.py."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    vmax = max(np.percentile(n[m > 0.5], 99) for n, m in maps)
    fig, axes = plt.subplots(1, len(maps), figsize=(6.5 * len(maps), 5.0))
    for ax, (noise, mask), label, s in zip(axes, maps, labels, stats):
        im = ax.imshow(np.where(mask > 0.5, noise, np.nan), origin="lower", cmap="magma",
                       vmin=0, vmax=vmax)
        ax.set_title(f"{label}\n{s['samples_per_texel']:.0f} samples/texel, "
                     f"mean rel. error {100 * s['mean_relative_error']:.2f} %")
        ax.set_xticks([])
        ax.set_yticks([])
    fig.colorbar(im, ax=list(axes), shrink=0.8, label="estimated relative standard error")
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=90)
    os.replace(tmp, path)  # atomic, like the bake's own writers


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/demo", help="output folder")
    parser.add_argument("--seconds", type=float, default=6.0, help="time budget per strategy")
    parser.add_argument("--size", type=int, default=256, help="lightmap resolution")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    scene, floor, description = omis.demo.build_scene(omis)
    print(f"omis {omis.__version__} demo: {description}")
    print(scene.effect_plan())
    print(f"baking the floor ({args.size}×{args.size}) for {args.seconds:g} s per strategy")

    runs = [("balance", "balance"), ("optimal-direct", "optimal")]
    results = []
    for strategy, name in runs:
        r = omis.bake_uv(scene, floor, args.size, args.size, strategy=strategy,
                         samples=1 << 30, time_budget=args.seconds, seed=1,
                         progress=progress_bar(strategy))
        r.write_exr(os.path.join(args.out, f"{name}.exr"))
        r.write_png(os.path.join(args.out, f"{name}.png"), view="Standard")
        r.write_png(os.path.join(args.out, f"{name}_filmic.png"), view="Filmic")
        results.append(r)
    noise_comparison(os.path.join(args.out, "noise_comparison.png"),
                     [(r.noise, r.mask) for r in results], [s for s, _ in runs],
                     [r.stats for r in results])

    lines = ["", f"{'strategy':<16} {'time (s)':>9} {'samples/texel':>14} "
                 f"{'mean rel. error':>16} {'max rel. error':>15}"]
    for (strategy, _), r in zip(runs, results):
        s = r.stats
        lines.append(f"{strategy:<16} {s['seconds']:>9.2f} {s['samples_per_texel']:>14.1f} "
                     f"{100 * s['mean_relative_error']:>15.2f}% {100 * s['max_relative_error']:>14.1f}%")
    b, o = (r.stats["mean_relative_error"] for r in results)
    lines.append(f"\nat equal time, optimal MIS leaves {o / b:.2f}× the relative error of the "
                 f"balance heuristic ({(o / b) ** 2:.2f}× its variance)")
    lines.append("errors are the bakes' own estimates (per-texel standard error / value)")
    table = "\n".join(lines)
    print(table)
    with open(os.path.join(args.out, "table.txt"), "w") as f:
        f.write(table.lstrip() + "\n")
    print(f"\nwrote {args.out}/: balance/optimal .exr .png _filmic.png, noise_comparison.png, table.txt")


if __name__ == "__main__":
    main()
