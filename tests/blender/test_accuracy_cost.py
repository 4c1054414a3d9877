"""Issue 12 item 8: what accuracy costs. After a bake, omis_bake.bake()'s dict, the
operator and the panel's scene.omis.last_* hold the error reached (mean and 95th
percentile of the texels' relative error), the time taken, and the time the next
halving of the error would cost, predicted from the bake's own measured convergence;
the prediction is checked against a second bake given that much more time.

    scripts/blender_run.sh tests/blender/test_accuracy_cost.py
"""

import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

import omis_bake  # noqa: E402
from omis_bake.job import BakeJob, accuracy_cost  # noqa: E402
from omis_bake.settings import settings_from  # noqa: E402

check = U.check


def setup():
    U.reset_scene()
    img = U.make_image("acc", 48)
    ob = U.image_grid("Floor", img, size=2.0, cuts=1)
    # A soft area light and a box casting a penumbra: texels of different noise.
    U.add_light('AREA', "lamp", energy=400.0, location=(0.3, 0.2, 1.2), size=0.8)
    U.add_box("Box", (0.4, 0.4, 0.4), (0.1, 0.0, 0.5))
    U.select_only([ob])
    return ob, img


def test_figures_everywhere():
    ob, img = setup()
    settings = settings_from(bpy.context.scene.omis, {"samples": 16, "margin": 0, "seed": 2})
    job = BakeJob(bpy.context, [ob], settings)
    job.run()
    stats = job.finish(bpy.context)
    unit = job.units[0]
    # Independent of the add-on's own reduction: the texels' noise over the mask.
    noise = unit.noise.reshape(-1)[unit.mask.reshape(-1) > 0].astype(np.float64)
    check(noise.size == stats["covered"], f"{noise.size} errors for {stats['covered']} texels")
    check(abs(stats["error_mean"] - noise.mean()) <= 1e-6 * noise.mean(), "error_mean")
    check(abs(stats["error_mean"] - stats["mean_relative_error"])
          <= 1e-4 * stats["mean_relative_error"], "error_mean disagrees with the core's mean")
    # "95 % of texels at most this": the smallest error ≥ 95 % of the texels' errors.
    p95 = np.sort(noise)[int(np.ceil(0.95 * noise.size)) - 1]
    check(np.sum(noise <= stats["error_p95"]) >= 0.95 * noise.size
          and abs(stats["error_p95"] - p95) <= 1e-6 * p95,
          f"error_p95 {stats['error_p95']} vs the 95th percentile {p95}")
    check(stats["error_p95"] > stats["error_mean"] > 0, "a penumbra has spread-out errors")
    check(stats["halving_seconds"] > 0 and stats["seconds"] > 0, "times")
    # A sample budget alone is one pass (two when the rounds do not divide it): no
    # convergence measured, the 1/√n bound.
    history = unit.stats["convergence"]
    check(len(history) in (1, 2) and not stats["halving_measured"], f"one pass: {history}")
    check(abs(stats["halving_seconds"] - 3.0 * history[-1]["seconds"])
          <= 1e-9 * stats["halving_seconds"], "the 1/√n bound is 3× the sampling time")
    props = bpy.context.scene.omis
    for name, key in (("last_mean_error", "mean_relative_error"),
                      ("last_error_p95", "error_p95"),
                      ("last_halving_seconds", "halving_seconds"), ("last_seconds", "seconds")):
        check(abs(getattr(props, name) - stats[key]) <= 1e-6 * max(1.0, stats[key]),
              f"scene.omis.{name} = {getattr(props, name)} vs {stats[key]}")
    # The operator leaves the same kind of figures for the panel.
    props.last_error_p95 = 0.0
    check(bpy.ops.omis.bake(samples=4, margin=0) == {'FINISHED'}, "operator")
    check(props.last_error_p95 > 0 and props.last_halving_seconds > 0,
          "operator left no accuracy figures")
    check(not props.last_halving_measured, "one pass cannot be a measured halving time")
    check(bpy.ops.omis.bake(samples=10 ** 6, time_budget=0.6, margin=0) == {'FINISHED'},
          "operator with a time limit")
    check(props.last_halving_measured, "a time limit's passes give a measured halving time")
    # One sequence per texel: the error is an upper estimate; a noise threshold measures it.
    check(not props.last_error_measured, "without a noise threshold the error is a bound")
    check(bpy.ops.omis.bake(samples=64, use_noise_target=True, noise_target=0.01, margin=0)
          == {'FINISHED'}, "operator with a noise threshold")
    check(props.last_error_measured, "a noise threshold's streams measure the error")


def test_halving_prediction():
    """The halving time predicted from a bake's measured convergence, against a second
    bake given that much more time: its mean error must be half the first's, within a
    factor F = 1.4 either way (ratio in [0.36, 0.70]). What moves the ratio when the
    prediction is right:
    - the mean error itself: the mean of ~1800 texels' estimates σ̂/√n (each with a
      relative spread of ~1/√(2·streams·rounds), small), stable to ~2 %;
    - the fitted β (least squares over ≤ 4 passes spanning ~8× in time, each point
      stable to ~2 %): ±0.03, i.e. ±(t2/t1)^0.03 ≈ ±3 % in the ratio;
    - where a budget ends in the pass schedule: passes end on powers of two of rounds
      and the time left takes tail blocks (core/bake/dyadic_schedule.h), so the error
      reached at a given time moves by up to ~10 % with the size of the last tail (the
      fit leaves tails out);
    - time itself: the two bakes run at different moments on a shared 2-core
      machine; a 25 % change in throughput moves the error by 1.25^β ≈ 1.17
      (β ≈ 0.7 measured here).
    Together ≈ 1.35 in the worst plausible case; F = 1.4. (Measured in three runs:
    ratios 0.41, 0.46, 0.47 — the fit is slightly conservative.)
    Under heavier load the throughput moved by more than 25 % (ratios 0.71-0.73 seen
    at load 6-8), which is the machine's doing, not the prediction's: the expected
    ratio is 0.5 scaled by the samples the second bake reached against those the
    first bake's rate buys in the predicted time, (n₂/n_pred)^(-β)."""
    setup()
    common = dict(samples=10 ** 6, margin=0, seed=9, use_optimal_mis=False,
                  heuristic='BALANCE')
    first_budget = 0.5
    first = omis_bake.bake(bpy.context, time_budget=first_budget, **common)
    history = first["units"][0]["convergence"]
    check(first["status"] == "time budget reached" and first["halving_measured"],
          f"a time limit gives passes and a measured convergence: {first['status']}, "
          f"{len(history)} passes")
    beta = first["units"][0]["halving_beta"]
    extra = first["halving_seconds"]
    check(abs(extra - history[-1]["seconds"] * (2 ** (1 / beta) - 1)) <= 1e-9 * extra,
          "halving = t·(2^(1/β) − 1)")
    second = omis_bake.bake(bpy.context, time_budget=first_budget + extra, **common)
    ratio = second["error_mean"] / first["error_mean"]
    end1, end2 = history[-1], second["units"][0]["convergence"][-1]
    # The samples the first bake's rate buys in the predicted sampling time.
    n_pred = end1["samples_per_texel"] * (end1["seconds"] + extra) / end1["seconds"]
    expected = 0.5 * (end2["samples_per_texel"] / n_pred) ** (-beta)
    print(f"β = {beta:.3f} over {first['units'][0]['halving_passes_fitted']} passes; "
          f"sampling {end1['seconds']:.3f} s + predicted {extra:.3f} s "
          f"(second bake sampled {end2['seconds']:.3f} s, {end2['samples_per_texel']:.0f} "
          f"of {n_pred:.0f} predicted samples): error {first['error_mean']:.5f} → "
          f"{second['error_mean']:.5f}, ratio {ratio:.3f} (want {expected:.3f} within ×1.4)")
    check(expected / 1.4 <= ratio <= expected * 1.4,
          f"the predicted halving time changed the error by {ratio:.3f}, not ≈ {expected:.3f}")


def test_cost_formula():
    units = [dict(halving_seconds=2.0, halving_measured=True),
             dict(halving_seconds=3.0, halving_measured=True)]
    cost = accuracy_cost(np.array([0.1, 0.2, 0.3, 0.4]), seconds=5.0, unit_stats=units)
    check(abs(cost["error_mean"] - 0.25) < 1e-12, "mean")
    check(abs(cost["halving_seconds"] - 5.0) < 1e-12, "every part halves: their sum")
    check(abs(cost["halving_total_seconds"] - 10.0) < 1e-12, "total")
    check(cost["halving_measured"], "measured when every part is")
    units[1]["halving_measured"] = False
    check(not accuracy_cost(np.ones(2), 1.0, units)["halving_measured"],
          "one part's bound makes the sum a bound")
    empty = accuracy_cost(np.zeros(0), seconds=1.0, unit_stats=[])
    check(empty["error_mean"] == 0 and empty["error_p95"] == 0 and
          not empty["halving_measured"], "nothing baked")


def main():
    for test in (test_cost_formula, test_figures_everywhere, test_halving_prediction):
        start = time.perf_counter()
        test()
        print(f"ok {test.__name__} ({time.perf_counter() - start:.2f} s)")


main()
