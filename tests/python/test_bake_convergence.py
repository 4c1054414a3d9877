"""Issue 12 item 8: a bake's convergence history and the halving prediction fitted
on it (omis.predict_halving, the C ABI's omisPredictBakeHalving), on synthetic
histories whose exponent is known, then on a real bake's own history."""
import math

import numpy as np
import pytest

import omis

from test_bake import floor_scene


def history(beta, times, c=0.2, noise=None, first_error=None):
    errors = c * np.asarray(times, float) ** -beta
    if noise is not None:
        errors = errors * noise
    records = [dict(samples_per_texel=10.0 * t, seconds=float(t), mean_relative_error=float(e))
               for t, e in zip(times, errors)]
    if first_error is not None:
        records[0]["mean_relative_error"] = first_error
    return records


DOUBLING = [0.05 * 2 ** k for k in range(7)]   # passes double in size


def test_exact_power_law_gives_its_exponent_and_halving_time():
    for beta in (0.5, 0.8, 1.2):
        h = omis.predict_halving(history(beta, DOUBLING))
        assert h["halving_measured"] and h["halving_passes_fitted"] == 4
        assert h["halving_beta"] == pytest.approx(beta, rel=1e-9)
        t = DOUBLING[-1]
        assert h["halving_seconds"] == pytest.approx(t * (2 ** (1 / beta) - 1), rel=1e-9)


def test_the_first_pass_is_not_fitted():
    # The first pass's error comes from one stream's independent-draw formula: an
    # outlier there must not move the exponent.
    h = omis.predict_halving(history(0.8, DOUBLING[:4], first_error=50.0))
    assert h["halving_passes_fitted"] == 3
    assert h["halving_beta"] == pytest.approx(0.8, rel=1e-9)


def test_noisy_history_within_its_standard_error():
    # Errors with 2 % multiplicative scatter (fixed seed). The least-squares slope
    # over the 4 fitted points (ln t spaced by ln 2: Σ(x − x̄)² = 5 (ln 2)² ≈ 2.40)
    # has a standard error of 0.02/√2.40 ≈ 0.013; 4 standard errors: 0.052.
    rng = np.random.default_rng(7)
    for _ in range(20):
        noise = np.exp(rng.normal(0.0, 0.02, len(DOUBLING)))
        h = omis.predict_halving(history(0.8, DOUBLING, noise=noise))
        assert abs(h["halving_beta"] - 0.8) <= 4 * 0.02 / math.sqrt(5 * math.log(2) ** 2)


def test_too_few_passes_assume_independent_draws():
    # 0 or 1 pass: β = 0.5 assumed, so halving takes 4× the samples, 3× the time
    # again (an upper bound). Two passes are the fewest a fit uses.
    for n in (0, 1):
        h = omis.predict_halving(history(0.9, DOUBLING[:n]))
        assert not h["halving_measured"] and h["halving_passes_fitted"] == 0
        assert h["halving_beta"] == 0.5
        t = DOUBLING[n - 1] if n else 0.0
        assert h["halving_seconds"] == pytest.approx(3.0 * t)
    h = omis.predict_halving(history(0.9, DOUBLING[:2]))
    assert h["halving_passes_fitted"] == 2 and h["halving_beta"] == pytest.approx(0.9)


def test_unusable_histories_fall_back():
    flat = [dict(seconds=t, mean_relative_error=0.1) for t in DOUBLING]
    assert not omis.predict_halving(flat)["halving_measured"]        # error does not fall
    short = history(0.8, [1.0, 1.05, 1.1, 1.15])                       # times span < 1.25×
    assert not omis.predict_halving(short)["halving_measured"]
    # A sample budget's last round as a pass of its own: few more samples.
    tail = history(0.8, [1.0, 2.0])
    tail[1]["samples_per_texel"] = 1.2 * tail[0]["samples_per_texel"]
    assert not omis.predict_halving(tail)["halving_measured"]
    zeros = [dict(seconds=t, mean_relative_error=0.0) for t in DOUBLING]  # nothing to halve
    h = omis.predict_halving(zeros)
    assert not h["halving_measured"] and h["halving_beta"] == 0.5


def test_exponent_is_kept_plausible():
    assert omis.predict_halving(history(3.0, DOUBLING))["halving_beta"] == 1.5
    assert omis.predict_halving(history(0.1, DOUBLING))["halving_beta"] == 0.25


def test_bad_history_names_the_argument():
    with pytest.raises(ValueError, match="passes"):
        omis.predict_halving([dict(seconds=-1.0, mean_relative_error=0.1)])
    with pytest.raises(ValueError, match="history"):
        omis.predict_halving([dict(seconds=1.0)])
    with pytest.raises(ValueError, match="history"):
        omis.predict_halving([(1.0, 0.1)])


def test_a_bake_records_its_passes():
    scene, mesh = floor_scene()
    # A sample budget alone: one pass (two when the rounds do not divide the
    # budget: the last round holds the rest), the 1/√n bound.
    one = omis.bake_uv(scene, mesh, 16, 16, samples=64, margin=0).stats
    assert len(one["convergence"]) in (1, 2) and not one["halving_measured"]
    assert one["convergence"][-1]["mean_relative_error"] == pytest.approx(
        one["mean_relative_error"], rel=1e-12)
    assert one["halving_seconds"] == pytest.approx(3.0 * one["convergence"][-1]["seconds"])
    # A noise target takes passes: samples grow, the error falls, the last record
    # is the result's own mean error.
    s = omis.bake_uv(scene, mesh, 16, 16, samples=4096, margin=0, noise_target=0.002,
                     strategy="balance").stats
    passes = s["convergence"]
    assert len(passes) == s["passes"] >= 3
    for a, b in zip(passes, passes[1:]):
        assert b["seconds"] > a["seconds"] and b["samples_per_texel"] > a["samples_per_texel"]
    assert passes[-1]["mean_relative_error"] < passes[0]["mean_relative_error"]
    assert passes[-1]["mean_relative_error"] == pytest.approx(s["mean_relative_error"], rel=1e-12)
    again = omis.predict_halving(passes)
    assert again["halving_beta"] == s["halving_beta"]
    assert again["halving_seconds"] == s["halving_seconds"]
