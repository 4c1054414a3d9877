#!/usr/bin/python3
"""Plot the direct-lighting benchmark: MSE against time per receiver.

Reads the CSV written by omis_bench_direct (--csv, default bench_direct.csv)
and writes a PNG with one panel per scene/receiver set, log-log axes, one line
per configuration swept over sample counts (4 ... 64 per receiver) and single
markers for the 20-sample configurations that were not swept. Lower-left is
better; a line lower at the same time is cheaper for the same accuracy.

    /usr/bin/python3 scripts/plot_direct_bench.py [bench_direct.csv] [-o out.png] [--cpu]
"""
import argparse
import csv
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {  # strategy -> line style, marker
    "alone": ("-", "o"),
    "balance": ("--", "s"),
    "power": (":", "v"),
    "optimal-direct": ("-", "D"),
    "optimal-progressive": ("-.", "^"),
}


def read_rows(path, cpu=False):
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["samples"] = int(r["samples"])
        r["rounds"] = int(r["rounds"])
        r["mse"] = float(r["mse"])
        # Time per receiver in µs: wall time (all threads working) or CPU time
        # summed over threads (not inflated when other jobs share the machine).
        ns = float(r["cpu_ns_per_sample"] if cpu else r["ns_per_sample"])
        r["us"] = ns * r["samples"] / 1000.0
        r["label"] = r["configuration"].split(" ")[0] + " " + r["strategy"]
    return rows


def series_of(rows):
    """(label, rows sorted by samples) per technique set, strategy and rounds kind."""
    series = OrderedDict()
    for r in rows:
        key = (r["techniques"], r["strategy"], r["rounds"] > 1)
        series.setdefault(key, []).append(r)
    return [(pts[0]["label"], sorted(pts, key=lambda r: r["us"])) for pts in series.values()]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv", nargs="?", default="bench_direct.csv")
    ap.add_argument("-o", "--output", default=None, help="PNG path (default: CSV name .png)")
    ap.add_argument("--cpu", action="store_true",
                    help="x axis: CPU time (all threads) instead of wall time per receiver")
    args = ap.parse_args()
    out = args.output or (args.csv.rsplit(".", 1)[0] + ".png")

    rows = read_rows(args.csv, args.cpu)
    panels = OrderedDict()
    for r in rows:
        panels.setdefault((r["scene"], r["receivers"]), []).append(r)

    fig, axes = plt.subplots(1, len(panels), figsize=(6.2 * len(panels), 7.0), squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, ((scene, receivers), prow) in zip(axes[0], panels.items()):
        for i, (label, pts) in enumerate(series_of(prow)):
            ls, marker = STYLE.get(pts[0]["strategy"], ("-", "o"))
            swept = len(pts) > 1
            ax.plot([p["us"] for p in pts], [p["mse"] for p in pts],
                    linestyle=ls if swept else "none", marker=marker,
                    markersize=5 if swept else 8, color=colors[i % len(colors)],
                    label=label + ("" if swept else " (20 spp)")
                    + (" 10 rounds" if pts[0]["rounds"] > 1 else ""))
            if swept:  # annotate the sample counts at the ends of the line
                for p in (pts[0], pts[-1]):
                    ax.annotate(str(p["samples"]), (p["us"], p["mse"]), fontsize=7,
                                textcoords="offset points", xytext=(4, 2),
                                color=colors[i % len(colors)])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"{scene} / {receivers}")
        ax.set_xlabel("CPU time per receiver, summed over threads (µs)" if args.cpu
                      else "wall time per receiver, all threads working (µs)")
        ax.set_ylabel("MSE of E/π over receivers")
        ax.grid(True, which="both", alpha=0.3)
        # Below the panel, so no line is hidden behind it.
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2,
                  frameon=False)
    fig.suptitle("omis direct lighting: accuracy vs time (lines: 4 … 64 samples per receiver)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
