"""omis.combine (SPEC §6) on 1-D problems with exact answers, and its errors.

Statistical checks: the mean of T seeded estimates must lie within 4 standard
errors (measured from the T estimates) of the exact integral — a 6e-5 miss
probability for a normal mean, reproducible because the seeds are fixed.
"""
import numpy as np
import pytest

import omis

K_SIGMA = 4.0

# Problem: f(x) = x² + 0.2 on (0,1), techniques 2x, 2(1−x), uniform, one each.
EXACT = 1.0 / 3.0 + 0.2


def draw(rng, rounds, counts=(1, 1, 1)):
    """Samples ordered round by round, with every technique's pdf."""
    samplers = [lambda u: np.sqrt(u), lambda u: 1 - np.sqrt(1 - u), lambda u: u]
    xs, techs = [], []
    for _ in range(rounds):
        for k, n in enumerate(counts):
            xs.extend(samplers[k](rng.random(n)))
            techs.extend([k] * n)
    x = np.array(xs)
    pdfs = np.stack([2 * x, 2 * (1 - x), np.ones_like(x)], axis=1)
    return x ** 2 + 0.2, pdfs, np.array(techs, dtype=np.int64)


def estimates(strategy, rounds, trials, seed, **options):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(trials):
        f, pdfs, tech = draw(rng, rounds)
        out.append(omis.combine(f, pdfs, tech, np.array([1, 1, 1]), strategy=strategy, **options)[0])
    return np.array(out)


def test_version():
    assert isinstance(omis.__version__, str) and omis.__version__.count(".") == 2


@pytest.mark.parametrize("strategy", ["balance", "power", "maximum", "cutoff", "optimal-progressive"])
def test_unbiased(strategy):
    e = estimates(strategy, rounds=8, trials=1500, seed=1)
    assert np.all(np.isfinite(e))
    se = e.std(ddof=1) / np.sqrt(len(e))
    assert abs(e.mean() - EXACT) <= K_SIGMA * se


def test_optimal_direct_consistent_and_better_than_balance():
    direct = estimates("optimal-direct", rounds=128, trials=600, seed=2)
    balance = estimates("balance", rounds=128, trials=600, seed=2)
    se = direct.std(ddof=1) / np.sqrt(len(direct))
    assert abs(direct.mean() - EXACT) <= K_SIGMA * se
    # f lies far from the pdfs' span balance fits: the exact ratio is ≈ 0.08.
    assert direct.var() < 0.25 * balance.var()


def test_rgb_and_variance():
    rng = np.random.default_rng(3)
    f, pdfs, tech = draw(rng, rounds=64)
    rgb = np.stack([f, 2 * f, np.zeros_like(f)], axis=1)
    est, var = omis.combine(rgb, pdfs, tech, [1, 1, 1], strategy="optimal-direct", return_variance=True)
    assert est.shape == (3,) and var.shape == (3,)
    assert est[1] == pytest.approx(2 * est[0], rel=1e-12)
    assert est[2] == 0.0 and var[2] == 0.0
    assert np.all(var >= 0)


def test_float32_is_accepted_and_options_apply():
    rng = np.random.default_rng(4)
    f, pdfs, tech = draw(rng, rounds=16)
    a = omis.combine(f.astype(np.float32), pdfs.astype(np.float32), tech.astype(np.int32), [1, 1, 1], strategy="balance")
    assert np.isfinite(a).all()
    # β = 1 turns the power heuristic into the balance heuristic.
    p1 = omis.combine(f, pdfs, tech, [1, 1, 1], strategy="power", beta=1.0)
    b = omis.combine(f, pdfs, tech, [1, 1, 1], strategy="balance")
    assert p1[0] == pytest.approx(b[0], rel=1e-12)
    # cutoff a = 0 keeps every technique: the balance heuristic again.
    c0 = omis.combine(f, pdfs, tech, [1, 1, 1], strategy="cutoff", cutoff=0.0)
    assert c0[0] == pytest.approx(b[0], rel=1e-12)


@pytest.fixture
def good():
    rng = np.random.default_rng(5)
    f, pdfs, tech = draw(rng, rounds=4)
    return f, pdfs, tech, np.array([1, 1, 1])


def call(args, **kw):
    f, pdfs, tech, counts = args
    return omis.combine(f, pdfs, tech, counts, **kw)


@pytest.mark.parametrize(
    "mutate, argument",
    [
        (lambda a: (a[0][:, None, None], a[1], a[2], a[3]), "f"),
        (lambda a: (a[0].astype(np.int64), a[1], a[2], a[3]), "f"),
        (lambda a: (np.where(np.arange(len(a[0])) == 3, np.nan, a[0]), a[1], a[2], a[3]), "f"),
        (lambda a: (a[0], a[1][:-1], a[2], a[3]), "pdfs"),
        (lambda a: (a[0], a[1].astype(object), a[2], a[3]), "pdfs"),
        (lambda a: (a[0], np.where(a[1] == a[1][0, 0], np.inf, a[1]), a[2], a[3]), "pdfs"),
        (lambda a: (a[0], -a[1], a[2], a[3]), "pdfs"),
        (lambda a: (a[0], a[1], a[2].astype(float), a[3]), "technique"),
        (lambda a: (a[0], a[1], a[2][:-1], a[3]), "technique"),
        (lambda a: (a[0], a[1], np.where(a[2] == 2, 7, a[2]), a[3]), "technique"),
        (lambda a: (a[0], a[1], a[2], np.array([1, 1])), "counts"),
        (lambda a: (a[0], a[1], a[2], np.array([1, 1, 3])), "counts"),
        (lambda a: (a[0], a[1], a[2], np.array([0, 0, 0])), "counts"),
        (lambda a: (a[0], a[1], a[2], np.array([1, -1, 1])), "counts"),
    ],
)
def test_bad_input_names_the_argument(good, mutate, argument):
    with pytest.raises(ValueError, match=f"^{argument}:"):
        call(mutate(good))


def test_zero_own_pdf_and_order_errors(good):
    f, pdfs, tech, counts = good
    pdfs = pdfs.copy()
    pdfs[0, tech[0]] = 0.0
    with pytest.raises(ValueError, match="own technique"):
        omis.combine(f, pdfs, tech, counts)
    f, pdfs, tech, counts = good
    swapped = tech.copy()
    swapped[0], swapped[3] = swapped[3], swapped[0]  # two samples of one technique in round 1
    pdfs = np.ones_like(pdfs)
    with pytest.raises(ValueError, match="round by round"):
        omis.combine(f, pdfs, np.array([0, 0, 1, 1, 2, 2, 0, 1, 2, 0, 1, 2]), counts)


def test_unknown_strategy_and_option(good):
    with pytest.raises(ValueError, match="^strategy:"):
        call(good, strategy="optimal")
    with pytest.raises(TypeError, match="gamma"):
        call(good, gamma=2.0)
    with pytest.raises(ValueError, match="beta"):
        call(good, strategy="power", beta=-1.0)


def test_singular_cases_are_finite():
    rng = np.random.default_rng(6)
    x = rng.random(20)
    pdfs = np.ones((20, 2))  # identical techniques
    tech = np.tile([0, 1], 10)
    for strategy in omis.STRATEGIES:
        e, v = omis.combine(x, pdfs, tech, [1, 1], strategy=strategy, return_variance=True)
        assert np.isfinite(e).all() and np.isfinite(v).all()
    zero = omis.combine(np.zeros(20), pdfs, tech, [1, 1])
    assert zero[0] == 0.0
