"""Equal-time benchmark: omis (balance, optimal-direct) against Cycles' own bake.

    bash scripts/blender_run.sh bench/bench_cycles.py [--out DIR] [--quick]
        [--scenes a,b,...] [--budgets 0.05,0.1,0.25,0.5,1,2] [--ref-seconds S] [--size N]
        [--techniques bsdf,uniform/solid-angle,...] [--equal-samples [--spp 4,16,64]]
        [--repeats N]

Scenes: every scene of the Cycles-agreement suite (tests/blender/cycles_scenes.py
SCENES, read at start-up; EXCLUDED lists those where omis and Cycles differ by
design, e.g. spot_radius) plus the demo room (scripts/blender_demo.py), each
baked into its float images (one per object where a scene gives each its own
lightmap: they are compared as one, stacked).

Per scene:
- Cycles: Diffuse bake, pass filter {DIRECT}, denoising and adaptive sampling
  off, margin 0. Its time per sample is measured first (t = t0 + k·spp, from
  two bakes); for a budget T it gets spp = max(1, round((T − t0)/k)), so its
  whole operator call (sync, BVH, sampling, write-back) takes about T.
- omis: the add-on's BakeJob (export + native bake + write-back, as
  omis_bake.bake does) with time_budget = T, the effect plan's techniques
  (or --techniques, to compare another choice), margin 0; strategies balance
  and optimal-direct. The log lists the plan's techniques per scene.
- Times on the plot are measured wall times of the whole bake call for both.
- References (converged): one per renderer (both box-filter each texel over its
  footprint; separate references keep any remaining modelling difference out
  of the noise comparison): Cycles at high spp for Cycles, omis balance
  (unbiased) at a long time budget for omis; each reference is the mean
  of two independent halves, whose difference estimates the reference's own
  noise, which is subtracted from every relMSE (printed as `ref floor`).
  A cell whose relMSE is below two standard errors of that difference
  (taken over texels) is not resolved by the references: it is reported at
  that resolution and marked "<" (its ratio is an upper bound).
  The two references are checked against each other (aggregate bias and the
  share of texels agreeing within 4σ, as the agreement test does).
- relMSE = mean over covered interior texels of (x − r)² / (r² + ε²), grey =
  mean of RGB, ε = 0.01 · mean(r) (keeps the fully shadowed texels finite).
- --repeats N: every cell (both renderers) is the mean over N runs with their own
  seeds (relMSE, time, samples per texel): a heavy-tailed scene's single runs
  spread by up to ~5× (demo_room, bench/results/low_spp.txt).

Writes DIR/bench_cycles.csv, DIR/bench_cycles.png (relMSE vs time, log-log, one
panel per scene) and DIR/table.txt, each naming the commit, date and command of
the run (`# commit:`, `# date:`, `# command:` lines at the top of the CSV and the
table; the plot's title). scripts/race_table.py copies them to bench/results/
and refreshes README.md's table.
"""

import argparse
import csv
import datetime
import os
import subprocess
import sys
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
import omis_test_utils as U  # noqa: E402
import cycles_scenes  # noqa: E402

from omis_bake.job import BakeJob  # noqa: E402
from omis_bake.settings import TECHNIQUE_NAME, settings_from  # noqa: E402


# Every scene of the agreement suite (new ones are picked up as they are
# appended), except those where omis and Cycles differ by design.
EXCLUDED = {"spot_radius"}  # spot cone per disk point: see cycles_scenes.scene_spot_radius
SCENES = {name: builder for name, builder in cycles_scenes.SCENES.items()
          if name not in EXCLUDED}
SCENES["demo_room"] = U.demo_room

STRATEGIES = ("cycles", "omis balance", "omis optimal")
TECHNIQUES_OVERRIDE = None  # set by --techniques


log = U.log
script_args = U.args


def grey(image):
    return U.pixels(image)[..., :3].astype(np.float64).mean(axis=2)


def clear(images):
    for image in images:
        U.set_pixels(image, (0.0, 0.0, 0.0, 0.0))


def cycles_run(objects, images, spp, seed):
    clear(images)
    seconds = U.cycles_bake(objects, int(spp), seed)
    return U.stacked([grey(image) for image in images]), seconds


def omis_run(objects, images, strategy, seed, seconds=0.0, samples=1 << 30):
    clear(images)
    U.select_only(objects)
    overrides = {"samples": int(samples), "time_budget": float(seconds), "margin": 0,
                 "seed": int(seed), "use_noise_target": False, "technique_mode": 'AUTO',
                 "use_clear": True}
    if TECHNIQUES_OVERRIDE:  # --techniques: compare another plan with the effect plan's
        overrides.update(technique_mode='MANUAL', techniques=TECHNIQUES_OVERRIDE)
    if strategy == "balance":
        overrides.update(use_optimal_mis=False, heuristic='BALANCE')
    else:
        overrides.update(use_optimal_mis=True, optimal_mode='DIRECT')
    start = time.perf_counter()
    job = BakeJob(bpy.context, objects, settings_from(bpy.context.scene.omis, overrides))
    job.run()
    stats = job.finish(bpy.context)
    wall = time.perf_counter() - start
    masks = {image.name: np.zeros((image.size[1], image.size[0]), bool) for image in images}
    for unit in job.units:
        masks[unit.target.name] |= unit.mask > 0.5
    return (U.stacked([grey(image) for image in images]), wall, stats,
            U.stacked([masks[image.name] for image in images]))


class Reference:
    """Mean of two independent halves; knows its own per-texel variance."""

    def __init__(self, a, b, mask):
        self.value = 0.5 * (a + b)
        self.var = 0.25 * (a - b) ** 2      # unbiased estimate of Var(mean of a, b)
        self.mask = mask
        self.eps2 = (0.01 * self.value[mask].mean()) ** 2

    def rel_mse(self, x):
        """relMSE of x and how finely it is resolved: two standard errors of
        the mean over texels. Once the reference's own noise (subtracted
        texel by texel) is larger than x's error, the difference can come out
        near zero or negative; below that resolution a cell is reported at it
        (an upper bound) instead."""
        m = self.mask
        r = self.value[m]
        d = ((x[m] - r) ** 2 - self.var[m]) / (r * r + self.eps2)  # minus the reference's noise
        return float(np.mean(d)), float(2.0 * np.std(d) / np.sqrt(d.size))

    def floor(self):
        m = self.mask
        r = self.value[m]
        return float(np.mean(self.var[m] / (r * r + self.eps2)))


def calibrate_cycles(objects, images, quick):
    """Cycles' operator time as t0 + k·spp, from bakes at two sample counts."""
    lo, hi = (1, 16) if quick else (2, 64)
    cycles_run(objects, images, 1, 99)                     # warm-up (kernels, caches)
    _, t_lo = cycles_run(objects, images, lo, 98)
    _, t_hi = cycles_run(objects, images, hi, 97)
    if t_hi / t_lo < 2.0 and not quick:                   # overhead-dominated: go further
        hi *= 8
        _, t_hi = cycles_run(objects, images, hi, 96)
    k = max((t_hi - t_lo) / (hi - lo), 1e-6)
    t0 = max(t_lo - k * lo, 0.0)
    return t0, k


def spp_for(seconds, t0, k):
    return max(1, int(round((seconds - t0) / k)))


def agreement(ref_c, ref_o, mask):
    """Cycles reference vs omis reference: aggregate bias and the share of texels
    within 4σ, as tests/blender/omis_test_utils.compare_to_cycles."""
    c, o = ref_c.value, ref_o.value
    sigma = np.sqrt(ref_c.var + ref_o.var)
    sigma = np.sqrt(U.box_mean(sigma ** 2, mask, 3))      # smooth the 2-sample variance
    ok = np.abs(o - c) <= 4 * sigma
    bias = float((o[mask].sum() - c[mask].sum()) / c[mask].sum())
    return bias, float(ok[mask].mean())


def run_scene(name, args):
    log(f"\n== {name} ==")
    U.reset_scene()
    builder = SCENES[name]
    objects = builder(args.size)
    bpy.context.view_layer.update()
    images = cycles_scenes.images_of(objects)

    t0, k = calibrate_cycles(objects, images, args.quick)
    log(f"  Cycles: {t0:.3f} s overhead + {1e3 * k:.2f} ms per spp "
        f"({args.size}² image, {bpy.context.scene.cycles.device}, "
        f"{bpy.context.scene.render.threads} threads)")

    # omis' covered texels (the same UV islands Cycles bakes).
    _, _, stats0, cover = omis_run(objects, images, "balance", 1, samples=1)
    mask = U.interior_texels(cover)
    plan = [line.strip() for line in (stats0["plan"] or "").splitlines()
            if line.strip().startswith(("+ ", "- "))]
    log(f"  plan: {'; '.join(plan) or '-'}; {int(mask.sum())} interior covered texels")

    # References.
    half = 0.5 * args.ref_seconds
    ref_spp = spp_for(half, t0, k)
    a, ta = cycles_run(objects, images, ref_spp, 1001)
    b, tb = cycles_run(objects, images, ref_spp, 1002)
    ref_c = Reference(a, b, mask)
    a, ta2, sa, _ = omis_run(objects, images, "balance", 2001, seconds=half)
    b, tb2, sb, _ = omis_run(objects, images, "balance", 2002, seconds=half)
    ref_o = Reference(a, b, mask)
    bias, agree = agreement(ref_c, ref_o, mask)
    log(f"  references: Cycles 2×{ref_spp} spp ({ta + tb:.1f} s, floor relMSE "
        f"{ref_c.floor():.2e}); omis balance 2×{sa['samples_per_texel']:.0f} samples/texel "
        f"({ta2 + tb2:.1f} s, floor {ref_o.floor():.2e}); omis vs Cycles reference: bias "
        f"{100 * bias:+.2f} %, {100 * agree:.1f} % of texels within 4σ")

    rows = []
    for i, budget in enumerate(args.budgets):
        spp = int(budget) if args.spp else spp_for(budget, t0, k)
        runs = {label: [] for label in STRATEGIES}
        # --repeats: a cell is the mean over runs with their own seeds (docstring).
        for j in range(args.repeats):
            seed = 10 + i + 100 * j
            x, t = cycles_run(objects, images, spp, seed)
            rel_mse, resolution = ref_c.rel_mse(x)
            runs["cycles"].append(dict(seconds=t, bake_seconds=t, samples_per_texel=spp,
                                       rel_mse=rel_mse, resolution=resolution))
            for strategy, label in (("balance", "omis balance"),
                                    ("optimal-direct", "omis optimal")):
                if args.equal_samples:  # Cycles' sample count, no time limit
                    x, t, s, _ = omis_run(objects, images, strategy, seed + 10, samples=spp)
                else:
                    x, t, s, _ = omis_run(objects, images, strategy, seed + 10, seconds=budget)
                rel_mse, resolution = ref_o.rel_mse(x)
                runs[label].append(dict(seconds=t, bake_seconds=s["bake_seconds"],
                                        samples_per_texel=s["samples_per_texel"],
                                        # the work: shadowed texels draw more per sample
                                        draws_per_texel=s.get("draws_per_texel",
                                                              s["samples_per_texel"]),
                                        rel_mse=rel_mse, resolution=resolution))
        for label in STRATEGIES:
            mean = {key: float(np.mean([run[key] for run in runs[label]]))
                    for key in runs[label][0]}
            # Below the references' resolution omis' cell is reported at it:
            # its ratio is then an upper bound (marked "<"); Cycles' unresolved
            # cells stay out of its fit (cycles_at) rather than flatter omis.
            mean["unresolved"] = mean["rel_mse"] < mean["resolution"]
            if mean["unresolved"] and label != "cycles":
                mean["rel_mse"] = mean["resolution"]
            rows.append(dict(scene=name, strategy=label, budget=budget,
                             ref_floor=(ref_c if label == "cycles" else ref_o).floor(), **mean))
        r = rows[-3:]
        log(f"  budget {budget:g} s: " + "; ".join(
            f"{row['strategy']} {row['seconds']:.2f} s {row['samples_per_texel']:.0f} spp "
            + (f"({row['draws_per_texel']:.1f} draws) " if "draws_per_texel" in row else "")
            + f"relMSE {row['rel_mse']:.2e}" for row in r))
    summary = dict(scene=name, t0=t0, k=k, ref_bias=bias, ref_agree=agree,
                   ref_spp=ref_spp, plan=stats0["plan"])
    return rows, summary


def cycles_at(rows, scene, seconds, key="seconds"):
    """Cycles' relMSE at a given time (or, key="samples_per_texel", at a given
    sample count): a quadratic fit through its points in log-log (a straight
    line with 3 points or fewer), continued past its end points along its end
    slopes. Not one power law: Cycles' error falls faster at its first samples
    (demo_room, 40 seeds per count: slope −2.0 from 1 to 2 spp, −1.4 to −1.6
    from 2 to 32), so a line through 4–180 spp put Cycles' error at 2 spp 1.6×
    too low and doubled omis' /C@spp there (bench/results/low_spp.txt)."""
    pts = [(r[key], r["rel_mse"]) for r in rows
           if r["scene"] == scene and r["strategy"] == "cycles" and r["rel_mse"] > 0
           and not r.get("unresolved")]
    t = np.log([p[0] for p in pts])
    e = np.log([p[1] for p in pts])
    if len(set(t)) < 2:  # one sample count at every budget (a loaded machine): no slope
        return float(np.exp(np.mean(e)))
    fit = np.polyfit(t, e, 2 if len(set(t)) >= 4 else 1)
    x = float(np.clip(np.log(seconds), t.min(), t.max()))
    slope = np.polyval(np.polyder(fit), x)
    return float(np.exp(np.polyval(fit, x) + slope * (np.log(seconds) - x)))


def _race_rule():
    """scripts/race_table.py's rule for budgets Cycles cannot bake in (one rule for
    the race's own table and README's)."""
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    from race_table import cycles_met_budget
    return cycles_met_budget


def table(rows, summaries, budgets):
    lines = [f"{'scene':<15} {'budget':>6} {'strategy':<13} {'time (s)':>8} {'spp':>7} "
             f"{'relMSE':>9} {'/Cycles':>8} {'/C@spp':>7}"]
    ratios, per_sample = {}, {}
    cycles_spp = {}
    for r in rows:
        if r["strategy"] == "cycles":
            cycles_spp.setdefault(r["scene"], []).append(r["samples_per_texel"])
    cycles_met_budget = _race_rule()
    cycles_row = {(r["scene"], r["budget"]): r for r in rows if r["strategy"] == "cycles"}
    lo_spp = {scene: min(spp) for scene, spp in cycles_spp.items()}
    hi_spp = {scene: max(spp) for scene, spp in cycles_spp.items()}
    for s in summaries:
        scene = s["scene"]
        for budget in budgets:
            for r in rows:
                if r["scene"] != scene or r["budget"] != budget:
                    continue
                ratio = r["rel_mse"] / cycles_at(rows, scene, r["seconds"])
                # Error per sample: against Cycles at omis' own sample count
                # (one Cycles sample is a light sample and a BSDF sample).
                at_spp = r["rel_mse"] / cycles_at(rows, scene, r["samples_per_texel"],
                                                   key="samples_per_texel")
                # Past Cycles' largest (or below its smallest) sample count the
                # fit is continued along its end slope: marked "*" and left out
                # of the @spp mean, which then compares measured counts only.
                inside = lo_spp[scene] <= r["samples_per_texel"] <= hi_spp[scene]
                r["ratio_vs_cycles"], r["ratio_at_spp"] = ratio, at_spp
                counted = cycles_met_budget(cycles_row[(scene, budget)], budget)
                if r["strategy"] != "cycles" and counted:
                    ratios.setdefault((scene, r["strategy"]), []).append(ratio)
                    if inside:
                        per_sample.setdefault((scene, r["strategy"]), []).append(at_spp)
                own = r["strategy"] == "cycles"
                lines.append(f"{scene:<15} {budget:>6g} {r['strategy']:<13} {r['seconds']:>8.2f} "
                             f"{r['samples_per_texel']:>7.0f} {r['rel_mse']:>9.2e} "
                             f"{1.0 if own else ratio:>8.2f} {1.0 if own else at_spp:>7.2f}"
                             + ("" if inside else "*") + ("" if counted else " (n/a)")
                             + ("<" if r.get("unresolved") and not own else ""))
    lines.append("")
    lines.append("relMSE of omis / relMSE of Cycles at equal wall time (geometric mean over the "
                 "budgets; Cycles interpolated by a log-log quadratic fit; goal: optimal ≤ 0.5;"
                 " (n/a): Cycles' one-sample bake overran the budget 1.5×, left out)")
    lines.append("(@spp: optimal's relMSE / Cycles' at the same samples per texel, geometric mean "
                 "over the counts inside Cycles' measured range; * marks the others; < marks "
                 "cells below the references' resolution, reported at it: upper bounds)")
    lines.append(f"{'scene':<15} {'balance':>8} {'optimal':>8} {'goal':>5}  {'@spp':>6} "
                 f"{'Cycles t0 (s)':>13} {'ms/spp':>7} {'refs: bias':>10} {'agree':>6}")
    for s in summaries:
        scene = s["scene"]
        b = float(np.exp(np.mean(np.log(ratios.get((scene, "omis balance"), [np.nan])))))
        o = float(np.exp(np.mean(np.log(ratios.get((scene, "omis optimal"), [np.nan])))))
        inside = per_sample.get((scene, "omis optimal"), [])
        q = float(np.exp(np.mean(np.log(inside)))) if inside else float("nan")
        s["ratio_balance"], s["ratio_optimal"], s["ratio_optimal_at_spp"] = b, o, q
        lines.append(f"{scene:<15} {b:>8.2f} {o:>8.2f} {'met' if o <= 0.5 else 'MISS':>5}  "
                     f"{q:>6.2f} {s['t0']:>13.3f} {1e3 * s['k']:>7.2f} {100 * s['ref_bias']:>+9.2f}% "
                     f"{100 * s['ref_agree']:>5.1f}%")
    return "\n".join(lines)


def plot(path, rows, summaries, measured):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401

    n = len(summaries)
    cols = min(4, n)
    nrows = (n + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 3.6 * nrows), squeeze=False)
    styles = {"cycles": ("tab:gray", "s"), "omis balance": ("tab:blue", "o"),
              "omis optimal": ("tab:red", "^")}
    for ax, s in zip(axes.ravel(), summaries):
        scene = s["scene"]
        for strategy in STRATEGIES:
            pts = sorted((r["seconds"], r["rel_mse"]) for r in rows
                         if r["scene"] == scene and r["strategy"] == strategy)
            color, marker = styles[strategy]
            ax.loglog([p[0] for p in pts], [max(p[1], 1e-12) for p in pts], marker=marker,
                      color=color, label=strategy)
        pts = sorted(r["seconds"] for r in rows if r["scene"] == scene and
                     r["strategy"] == "cycles")
        half = [0.5 * cycles_at(rows, scene, t) for t in pts]
        ax.loglog(pts, half, ":", color="tab:gray", label="0.5 × Cycles (goal)")
        ax.set_title(f"{scene}  (optimal/Cycles {s['ratio_optimal']:.2f})", fontsize=10)
        ax.set_xlabel("bake time (s, wall)")
        ax.set_ylabel("relMSE")
        ax.grid(True, which="both", alpha=0.3)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.set_xticks(sorted({r["budget"] for r in rows}))
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    axes.ravel()[0].legend(fontsize=8)
    fig.suptitle("Direct-lighting bake, equal time: Cycles vs omis (Blender "
                 f"{bpy.app.version_string}; omis {measured})")
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=100)
    os.replace(tmp, path)


def provenance(argv):
    """(commit, date, command) of this run: the source tree's commit ('+' when tracked
    files differ from it), the UTC date, and the command line that reproduces it."""
    def git(*a):
        try:
            return subprocess.run(["git", "-C", ROOT, *a], capture_output=True, text=True,
                                  check=True).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            return ""
    commit = git("rev-parse", "--short=7", "HEAD") or "unknown"
    if git("status", "--porcelain", "--untracked-files=no"):
        commit += "+"
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    command = " ".join(["bash scripts/blender_run.sh bench/bench_cycles.py", *argv])
    return commit, date, command


def main():
    parser = argparse.ArgumentParser(prog="bench_cycles.py", description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/bench_cycles")
    parser.add_argument("--quick", action="store_true", help="smoke run (< 1 minute)")
    parser.add_argument("--scenes", default=None, help="comma-separated; default: all")
    parser.add_argument("--budgets", default=None, help="seconds, comma-separated")
    parser.add_argument("--ref-seconds", type=float, default=None,
                        help="time per reference (two halves), per renderer")
    parser.add_argument("--size", type=int, default=None, help="image size (texels)")
    parser.add_argument("--techniques", default=None,
                        help="comma-separated technique names (SPEC §3) for omis instead "
                             "of the effect plan's choice, e.g. uniform/solid-angle,bsdf")
    parser.add_argument("--equal-samples", action="store_true",
                        help="omis takes Cycles' samples per texel at each budget instead of "
                             "the time budget (error per sample; read the @spp column)")
    parser.add_argument("--repeats", type=int, default=1,
                        help="runs per cell and renderer (seeds), averaged")
    parser.add_argument("--spp", default=None,
                        help="with --equal-samples: Cycles' samples per texel, comma-separated, "
                             "instead of those the budgets buy (the budget column then shows "
                             "them): the same counts on a loaded machine")
    args = parser.parse_args(script_args())
    if args.repeats < 1:
        raise SystemExit("--repeats: must be at least 1")
    if args.spp and not args.equal_samples:
        raise SystemExit("--spp: needs --equal-samples")
    if args.techniques:
        global TECHNIQUES_OVERRIDE
        names = {name: ident for ident, name in TECHNIQUE_NAME.items()}
        unknown = [t for t in args.techniques.split(",") if t not in names]
        if unknown:
            raise SystemExit(f"--techniques: unknown {', '.join(unknown)}; known: "
                             f"{', '.join(names)}")
        TECHNIQUES_OVERRIDE = frozenset(names[t] for t in args.techniques.split(","))
    if args.quick:
        scenes = ["area", "demo_room"]
        budgets, ref_seconds, size = [0.1, 0.2, 0.4], 2.0, 64
    else:
        scenes = list(SCENES)
        budgets, ref_seconds, size = [0.05, 0.1, 0.25, 0.5, 1.0, 2.0], 16.0, 128
    if args.scenes:
        scenes = args.scenes.split(",")
    for name in scenes:
        if name not in SCENES:
            raise SystemExit(f"unknown scene {name!r}; known: {', '.join(SCENES)}")
    args.budgets = [float(b) for b in args.budgets.split(",")] if args.budgets else budgets
    if args.spp:
        args.budgets = [float(int(n)) for n in args.spp.split(",")]
    args.ref_seconds = args.ref_seconds or ref_seconds
    args.size = args.size or size
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    commit, date, command = provenance(script_args())
    header = f"# commit: {commit}\n# date: {date}\n# command: {command}\n"

    start = time.perf_counter()
    log(f"bench_cycles: scenes {', '.join(scenes)}; budgets {args.budgets} s; references "
        f"{args.ref_seconds:g} s each; {args.size}² images")
    rows, summaries = [], []
    for name in scenes:
        r, s = run_scene(name, args)
        rows += r
        summaries.append(s)
    text = table(rows, summaries, args.budgets)
    log("\n" + text)
    with open(os.path.join(out, "table.txt"), "w") as f:
        f.write(header + text + "\n")
    with open(os.path.join(out, "bench_cycles.csv"), "w", newline="") as f:
        f.write(header)
        fields = ["scene", "strategy", "budget", "seconds", "bake_seconds",
                  "samples_per_texel", "draws_per_texel", "rel_mse", "resolution", "unresolved", "ref_floor",
                  "ratio_vs_cycles", "ratio_at_spp"]
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    plot(os.path.join(out, "bench_cycles.png"), rows, summaries, f"{commit}, {date}")
    log(f"\nwrote {out}/: bench_cycles.csv, bench_cycles.png, table.txt "
        f"({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
