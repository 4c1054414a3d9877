#!/usr/bin/env python3
"""Refresh README.md's headline table (omis against Cycles at equal time) from the
race's CSV, with the commit, date and command the race was run with.

    python3 scripts/race_table.py                        # from bench/results/cycles_vs_omis.csv
    python3 scripts/race_table.py --from out/bench_cycles  # copy a new race in first

--from DIR copies DIR/bench_cycles.{csv,png} and DIR/table.txt (what
bench/bench_cycles.py writes) to bench/results/cycles_vs_omis.{csv,png,txt}.
The table replaces the lines between `<!-- race-table:begin -->` and
`<!-- race-table:end -->` in README.md; nothing else is touched. --check exits
with 1 when README.md's table differs from the CSV's (changes nothing).

Per scene: relMSE(omis) ÷ relMSE(Cycles) at equal wall time (the CSV's
ratio_vs_cycles: Cycles' error interpolated at omis' time), geometric mean over
the time budgets, as bench_cycles.py's own summary. Standard library only.
"""

import argparse
import csv
import math
import os
import shutil
import sys
import textwrap

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RESULTS = os.path.join(ROOT, "bench", "results")
BEGIN, END = "<!-- race-table:begin -->", "<!-- race-table:end -->"
GOAL = 0.5  # optimal ≤ half Cycles' relMSE at equal time on every scene
# In the mean over scenes a scene counts at least this (the table's 0.00 rows): a scene
# that is nearly noise-free for omis would otherwise dominate the mean (the race
# history's means since the 2026-12-01 races are taken this way).
SCENE_FLOOR = 0.005


def read_race(path):
    """(provenance dict, rows) from a bench_cycles CSV: `# key: value` lines, then the CSV."""
    meta, lines = {}, []
    with open(path, newline="") as f:
        for line in f:
            if line.startswith("#"):
                key, _, value = line[1:].partition(":")
                meta[key.strip()] = value.strip()
            else:
                lines.append(line)
    rows = list(csv.DictReader(lines))
    if not rows:
        raise SystemExit(f"{path}: no rows")
    for key in ("commit", "date", "command"):
        if key not in meta:
            raise SystemExit(f"{path}: no '# {key}:' line (bench/bench_cycles.py writes them)")
    return meta, rows


# A budget counts for a scene only where Cycles' bake took at most this many times
# the budget: below its own fixed cost (e.g. building an image world's importance
# map, ~0.8 s) Cycles bakes nothing in that time, its 1-sample cells all sit at one
# time, and the log-log fit's end slope sends its "error at omis' time" to any
# value (0.00 and 50000 in the same race). Such cells are listed, not averaged.
CYCLES_OVERRUN = 1.5


def cycles_met_budget(cycles_row, budget):
    """Whether Cycles could bake in this budget: not when even its single sample took
    over CYCLES_OVERRUN × the budget (a longer bake of more samples is only the
    machine's noise in its calibration, which the fit absorbs)."""
    return (float(cycles_row["samples_per_texel"]) > 1
            or float(cycles_row["seconds"]) <= CYCLES_OVERRUN * budget)


def geomean(values):
    return math.exp(sum(math.log(max(v, 1e-12)) for v in values) / len(values))


def summarise(rows):
    """Per scene, in the CSV's order: (scene, balance, optimal) geometric means, and the
    budgets; the largest single cell of either strategy."""
    ratios, budgets = {}, []
    worst = (0.0, None)
    cycles_row = {(r["scene"], r["budget"]): r for r in rows if r["strategy"] == "cycles"}
    skipped = {}
    for r in rows:
        if r["strategy"] == "cycles":
            continue
        if not cycles_met_budget(cycles_row[(r["scene"], r["budget"])], float(r["budget"])):
            skipped.setdefault(r["scene"], set()).add(float(r["budget"]))
            continue
        ratio = float(r["ratio_vs_cycles"])
        ratios.setdefault(r["scene"], {}).setdefault(r["strategy"], []).append(ratio)
        budget = float(r["budget"])
        if budget not in budgets:
            budgets.append(budget)
        if ratio > worst[0]:
            worst = (ratio, f"{r['strategy'].split()[-1]} {ratio:.2f}, {r['scene']} at {budget:g} s")
    scenes = [(scene, geomean(s["omis balance"]), geomean(s["omis optimal"]))
              for scene, s in ratios.items()]
    return scenes, sorted(budgets), worst[1], skipped


def table(meta, rows):
    scenes, budgets, worst, skipped = summarise(rows)
    every = sorted({float(r["budget"]) for r in rows})
    met = sum(1 for _, _, o in scenes if o <= GOAL)
    lines = [
        f"Measured at commit `{meta['commit']}` on {meta['date']} with",
        f"`{meta['command']}` (budgets {', '.join(f'{b:g}' for b in every)} s;",
        "`bench/results/cycles_vs_omis.{txt,csv,png}`). relMSE(omis) ÷ relMSE(Cycles) at",
        "equal wall time, geometric mean over the budgets: below 1 omis is cleaner than",
        "Cycles for the same wait. Single scenes swing by up to ~2× between runs on a",
        "shared machine.",
        "",
        "| scene | omis balance | omis optimal |",
        "|---|---|---|",
    ]
    lines += [f"| {scene} | {b:.2f} | **{o:.2f}** |" for scene, b, o in scenes]
    if skipped:
        lines += ["", textwrap.fill(
            f"Budgets left out where Cycles' one-sample bake took over {CYCLES_OVERRUN:g}× "
            "the budget (its fixed cost alone exceeds it: there is no Cycles bake of that "
            "time to compare with): " + "; ".join(
                f"{scene} {', '.join(f'{b:g}' for b in sorted(bs))} s"
                for scene, bs in skipped.items()) + ".", 84, break_on_hyphens=False)]
    summary = (
        f"Optimal ≤ {GOAL} on {met} of {len(scenes)} scenes; geometric mean over the scenes "
        f"(each counted at least {SCENE_FLOOR}): optimal "
        f"{geomean([max(o, SCENE_FLOOR) for _, _, o in scenes]):.3f}, balance "
        f"{geomean([max(b, SCENE_FLOOR) for _, b, _ in scenes]):.3f}; largest single cell: "
        f"{worst}.")
    lines += ["", textwrap.fill(summary, 84, break_on_hyphens=False)]
    return "\n".join(lines)


def replace_block(text, block):
    if text.count(BEGIN) != 1 or text.count(END) != 1 or text.index(BEGIN) > text.index(END):
        raise SystemExit(f"README.md: needs one {BEGIN} line before one {END} line")
    head, rest = text.split(BEGIN)
    _, tail = rest.split(END)
    return f"{head}{BEGIN}\n{block}\n{END}{tail}"


def copy_race(src):
    pairs = (("bench_cycles.csv", "cycles_vs_omis.csv"), ("bench_cycles.png", "cycles_vs_omis.png"),
             ("table.txt", "cycles_vs_omis.txt"))
    for name, _ in pairs:
        if not os.path.isfile(os.path.join(src, name)):
            raise SystemExit(f"--from: {os.path.join(src, name)} not found (run "
                             "bench/bench_cycles.py first)")
    read_race(os.path.join(src, "bench_cycles.csv"))  # refuse a CSV without provenance
    for name, target in pairs:
        shutil.copyfile(os.path.join(src, name), os.path.join(RESULTS, target))
        print(f"copied {name} -> bench/results/{target}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--from", dest="src", help="a bench_cycles.py output directory to copy in")
    parser.add_argument("--csv", default=os.path.join(RESULTS, "cycles_vs_omis.csv"))
    parser.add_argument("--readme", default=os.path.join(ROOT, "README.md"))
    parser.add_argument("--check", action="store_true",
                        help="only check that README.md's table is up to date")
    args = parser.parse_args(argv)
    if args.src:
        copy_race(args.src)
    meta, rows = read_race(args.csv)
    with open(args.readme, encoding="utf-8") as f:
        text = f.read()
    new = replace_block(text, table(meta, rows))
    if args.check:
        if new != text:
            print("README.md's race table is out of date: run python3 scripts/race_table.py")
            return 1
        return 0
    if new != text:
        tmp = args.readme + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(new)
        os.replace(tmp, args.readme)
    print(f"README.md: race table of {meta['commit']} ({meta['date']})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
