"""Property-based fuzzing of every public function of the Python API (issue 11).

Hypothesis draws malformed arrays (wrong shapes, dtypes, objects), extreme
magnitudes (denormals to 1.7e308, NaN, Inf) and random call orders. Whatever
comes in, a call must either succeed or raise ValueError / TypeError (omis's
own errors) — never crash the interpreter or raise anything else — and a call
whose numeric inputs are all finite must return no NaN. Examples are bounded
and derandomized, so the run is reproducible and takes seconds.
"""
import math
import os
import warnings

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, assume, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import omis  # noqa: E402

# OMIS_FUZZ_EXAMPLES=2000 (and OMIS_FUZZ_RANDOM=1) for a longer local search.
FUZZ = settings(max_examples=int(os.environ.get("OMIS_FUZZ_EXAMPLES", 50)), deadline=None,
                derandomize=not os.environ.get("OMIS_FUZZ_RANDOM"), database=None,
                suppress_health_check=list(HealthCheck))
ALLOWED = (ValueError, TypeError, omis.Cancelled)

MAGNITUDES = [0.0, 1.0, -1.0, 0.5, 3.0, 1e-320, 1e-160, 1e-30, 1e-7, 1e5, 1e30, 1e155,
              1e200, 1.7e308, -1e308]
NONFINITE = [math.nan, math.inf, -math.inf]
finite = st.one_of(st.sampled_from(MAGNITUDES), st.floats(-10, 10, allow_nan=False))
number = st.one_of(finite, st.sampled_from(NONFINITE))
junk = st.sampled_from([None, "2", "", b"x", [], [1, 2], {}, object(), 1j, True,
                        np.array(["a"]), np.zeros((2, 2, 2)), np.float16(1), 2**70])
valid_triple = st.one_of(st.tuples(finite, finite, finite), finite)
triple = st.one_of(*[valid_triple] * 8, st.tuples(number, number, number), junk)
DTYPES = [np.float64, np.float32, np.float16, np.int32, np.int64, np.uint32, np.bool_,
          np.complex128, object]


def array(shape, elements=finite, dtype=np.float64):
    """An array of shape with the given elements, sometimes of a wrong dtype or shape."""
    def build(values, dtype_, shape_):
        try:
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore")  # overflowing casts are the point
                return np.array(values, dtype=dtype_).reshape(shape_)
        except (ValueError, TypeError, OverflowError):
            return np.zeros(shape_)
    size = int(np.prod(shape))
    good = st.lists(elements, min_size=size, max_size=size).map(
        lambda v: build(v, dtype, shape))
    wrong_dtype = st.tuples(st.lists(elements, min_size=size, max_size=size),
                            st.sampled_from(DTYPES)).map(lambda a: build(a[0], a[1], shape))
    wrong_shape = st.lists(st.integers(0, 4), min_size=0, max_size=3).map(
        lambda s: np.ones(tuple(s)))
    return st.one_of(*[good] * 8, wrong_dtype, wrong_shape, junk)  # mostly well formed


def is_finite_input(*values):
    for v in values:
        try:
            a = np.asarray(v, dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            continue
        if not np.all(np.isfinite(a)):
            return False
    return True


def no_nan(*outputs):
    for out in outputs:
        a = np.asarray(out, dtype=np.float64)
        assert not np.any(np.isnan(a)), out


def call(function, *args, **kwargs):
    """function(*args, **kwargs), or None when it refused with an allowed error."""
    try:
        return function(*args, **kwargs)
    except ALLOWED:
        return None
    except RuntimeError as e:
        # omis's call-order errors (a scene used before or after commit) and
        # I/O failures of the writers.
        assert "commit" in str(e) or "cannot write" in str(e), e
        return None


STRATEGIES = ["balance", "power", "maximum", "cutoff", "optimal-direct",
              "optimal-progressive"]
strategy_name = st.one_of(*[st.sampled_from(STRATEGIES)] * 8,
                          st.sampled_from(["", "bogus", "balance\0x"]))
COUNTS = [-1, 0, 1, 2, 3, 2**31 - 1, 2**31, 2**63]


@FUZZ
@given(data=st.data(), S=st.sampled_from([0, 1, 4, 8]), N=st.sampled_from([1, 2, 3]),
       C=st.sampled_from([1, 3]))
def test_combine(data, S, N, C):
    f = data.draw(array((S, C)))
    pdfs = data.draw(array((S, N), elements=st.one_of(*[finite.map(abs)] * 8, number)))
    technique = data.draw(st.one_of(
        *[st.just(np.arange(S) % N)] * 6, array((S,), st.integers(-2, 4), np.int64)))
    counts = data.draw(st.one_of(*[st.just([1] * N)] * 6,
                                 st.lists(st.sampled_from(COUNTS), min_size=0, max_size=4),
                                 junk))
    options = data.draw(st.dictionaries(
        st.sampled_from(["beta", "cutoff", "return_variance", "bogus"]),
        st.one_of(*[finite.map(abs)] * 4, number, junk, st.booleans()), max_size=2))
    strategy = data.draw(strategy_name)
    out = call(omis.combine, f, pdfs, technique, counts, strategy=strategy, **options)
    if out is not None and is_finite_input(f, pdfs, list(options.values())):
        no_nan(*(out if isinstance(out, tuple) else (out,)))


def add_light(scene, data):
    kind = data.draw(st.sampled_from(["rect", "ellipse", "disk", "point", "spot", "sun",
                                      "world", "flags"]))
    t = lambda: data.draw(triple)  # noqa: E731
    x = lambda: data.draw(st.one_of(*[finite.map(abs)] * 6, number, junk))  # noqa: E731
    calls = {
        "rect": lambda: scene.add_rect_light(t(), t(), t(), t(), spread=x()),
        "ellipse": lambda: scene.add_ellipse_light(t(), t(), t(), t()),
        "disk": lambda: scene.add_disk_light(t(), t(), x(), t()),
        "point": lambda: scene.add_point_light(t(), t(), radius=x()),
        "spot": lambda: scene.add_spot_light(t(), t(), t(), spot_size=x(), spot_blend=x(),
                                             radius=x()),
        "sun": lambda: scene.add_sun_light(t(), t(), angle=x()),
        "world": lambda: scene.set_world(t()),
        "flags": lambda: scene.set_light_flags(data.draw(st.one_of(st.integers(-2, 5), junk)),
                                               cast_shadow=data.draw(st.booleans()),
                                               visible_to_bsdf=data.draw(st.booleans())),
    }
    call(calls[kind])


def add_mesh(scene, data):
    V = data.draw(st.sampled_from([0, 3, 4]))
    T = data.draw(st.sampled_from([0, 1, 2]))
    vertices = data.draw(array((V, 3), dtype=data.draw(st.sampled_from([np.float32, np.float64]))))
    triangles = data.draw(array((T, 3), st.integers(-1, 5), np.uint32))
    uvs = data.draw(st.one_of(st.none(), array((3 * T, 2))))
    emission = data.draw(st.one_of(st.none(), triple))
    return call(scene.add_mesh, vertices, triangles, uvs=uvs, emission=emission)


def floor(scene, scale, shift):
    v = (np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]) * scale + shift)
    t = np.array([[0, 1, 2], [0, 2, 3]], np.uint32)
    uv = (np.array([[-1, -1], [1, -1], [1, 1], [-1, -1], [1, 1], [-1, 1]]) + 1) / 2
    return call(scene.add_mesh, v, t, uvs=uv)


TECHNIQUES = ["bsdf", "uniform/area", "uniform/solid-angle", "power/area", "unoccluded/parallel"]
technique_list = st.one_of(st.none(), st.none(),
                           *[st.lists(st.sampled_from(TECHNIQUES), min_size=1, max_size=3,
                                      unique=True)] * 4,
                           st.lists(st.sampled_from(TECHNIQUES + ["bogus", ""]), max_size=3),
                           st.just("bsdf,uniform/area"), junk)


def small_counts(data, techniques):
    if techniques is None and data.draw(st.integers(0, 4)):
        return None  # mostly the valid pairing
    n = len(techniques) if isinstance(techniques, list) else 2
    valid = st.lists(st.sampled_from([1, 2, 4]), min_size=n, max_size=n)
    counts = data.draw(st.one_of(*[valid] * 4, st.none(),
                                 st.lists(st.sampled_from(COUNTS + [4, 8]), min_size=n,
                                          max_size=n), junk))
    # Valid huge counts would run for minutes: keep totals small or overflowing.
    if isinstance(counts, list):
        total = sum(c for c in counts if c > 0)
        assume(total <= 16 or max(counts) >= 2**31 or total > 2**31 - 1)
    return counts


@FUZZ
@given(data=st.data())
def test_scene_call_orders(data):
    """Random sequences of scene building, commit, lighting and baking."""
    scene = omis.Scene()
    scale = data.draw(st.sampled_from([1.0, 1e-7, 1e5, 1e-30, 1e30]))
    shift = data.draw(st.sampled_from([0.0, 1e5, -3e3]))
    mesh = floor(scene, scale, shift)
    add_light(scene, data)
    # Mostly build, commit, then use; any other order too.
    usual = ["light", "commit", "light_points", "plan", "bake"]
    steps = data.draw(st.one_of(st.just(usual), st.permutations(usual),
                                st.lists(st.sampled_from(usual + ["mesh"]), max_size=6)))
    for step in steps:
        if step == "light":
            add_light(scene, data)
        elif step == "mesh":
            add_mesh(scene, data)
        elif step == "commit":
            call(scene.commit)
        elif step == "plan":
            techniques = data.draw(technique_list)
            call(scene.effect_plan, techniques=techniques,
                 samples=small_counts(data, techniques))
        elif step == "light_points":
            light_points(scene, data, scale, shift)
        else:
            bake(scene, data, mesh)


def light_points(scene, data, scale, shift):
    P = data.draw(st.sampled_from([0, 1, 3]))
    points = data.draw(st.one_of(st.just(np.array([[0.2, 0.1, 0.0]] * P) * scale + shift),
                                 array((P, 3))))
    normals = data.draw(st.one_of(st.just(np.array([[0.0, 0.0, 1.0]] * P)), array((P, 3))))
    techniques = data.draw(technique_list)
    samples = small_counts(data, techniques)
    kwargs = data.draw(st.fixed_dictionaries({}, optional={
        "rounds": st.one_of(st.sampled_from([-1, 0, 1, 2, 2**31]), junk),
        "strategy": strategy_name,
        "beta": st.one_of(number, junk), "cutoff": st.one_of(number, junk),
        "seed": st.one_of(st.sampled_from([0, 1, -1, 2**64, 2**63]), junk),
        "progress": st.sampled_from([None, 5, lambda f: True, lambda f: False]),
        "return_stats": st.booleans()}))
    out = call(omis.direct_lighting, scene, points, normals, techniques, samples, **kwargs)
    if out is None:
        return
    if is_finite_input(points, normals, kwargs.get("beta", 0), kwargs.get("cutoff", 0)):
        no_nan(out[0], out[1])


def bake(scene, data, mesh):
    techniques = data.draw(technique_list)
    counts = small_counts(data, techniques)
    target = data.draw(st.sampled_from(["uv", "POINT", "CORNER", "bogus"]))
    kwargs = data.draw(st.fixed_dictionaries({}, optional={
        "samples": st.one_of(st.sampled_from([-1, 0, 1, 4, 16, 2**40]), junk),
        "strategy": strategy_name,
        "time_budget": st.one_of(st.none(), number, junk),
        "noise_target": st.one_of(st.none(), number, junk),
        "seed": st.one_of(st.sampled_from([0, 7, -1, 2**64]), junk),
        "smooth_normals": st.booleans(),
        "progress": st.sampled_from([None, 5, lambda f: True, lambda f: False]),
        "threads": st.sampled_from([-1, 0, 1, 2])}))
    mesh_id = data.draw(st.one_of(st.just(mesh if mesh is not None else 0),
                                  st.sampled_from([-1, 7, 2**40])))
    if target == "uv":
        size = data.draw(st.sampled_from([(4, 4), (0, 4), (-1, 2), (3, 1)]))
        result = call(omis.bake_uv, scene, mesh_id, *size, techniques=techniques,
                      counts=counts, **kwargs)
    else:
        result = call(omis.bake_vertices, scene, mesh_id, domain=target,
                      techniques=techniques, counts=counts, **kwargs)
    if result is None:
        return
    no_nan(result.value if hasattr(result, "value") else [])
    path = data.draw(st.sampled_from(["/nonexistent/dir/x.exr", "", "a\0b.exr", "/"]))
    call(result.write_exr, path)
    call(result.write_png, path, exposure=data.draw(number))


# Well-formed calls with extreme magnitudes: the paths past argument checking.

@FUZZ
@given(data=st.data(), rounds=st.sampled_from([1, 2]), N=st.sampled_from([1, 2, 3]),
       C=st.sampled_from([1, 3]), strategy=st.sampled_from(STRATEGIES))
def test_combine_well_formed(data, rounds, N, C, strategy):
    S = rounds * N
    f = np.array(data.draw(st.lists(finite, min_size=S * C, max_size=S * C))).reshape(S, C)
    pdfs = np.abs(np.array(data.draw(st.lists(finite, min_size=S * N, max_size=S * N))))
    pdfs = pdfs.reshape(S, N)
    technique = np.arange(S) % N
    pdfs[np.arange(S), technique] = np.where(pdfs[np.arange(S), technique] > 0,
                                             pdfs[np.arange(S), technique], 1.0)
    options = {"beta": data.draw(st.sampled_from([0.5, 1.0, 2.0, 7.0, 1e3])),
               "cutoff": data.draw(st.sampled_from([0.0, 0.1, 1.0]))}
    out = call(omis.combine, f, pdfs, technique, [1] * N, strategy=strategy,
               return_variance=True, **options)
    if out is not None:
        no_nan(*out)


def valid_light(scene, data):
    t = lambda: data.draw(st.tuples(finite, finite, finite))  # noqa: E731
    e = lambda: data.draw(st.sampled_from([0.0, 1.0, 1e-300, 1e-30, 1e30, 1e99]))  # noqa: E731
    x = lambda: abs(data.draw(finite))  # noqa: E731
    kind = data.draw(st.sampled_from(["rect", "ellipse", "disk", "point", "spot", "sun", "world"]))
    calls = {
        "rect": lambda: scene.add_rect_light(t(), t(), t(), e(), two_sided=data.draw(st.booleans())),
        "ellipse": lambda: scene.add_ellipse_light(t(), t(), t(), e()),
        "disk": lambda: scene.add_disk_light(t(), t(), x(), e()),
        "point": lambda: scene.add_point_light(t(), e(), radius=x()),
        "spot": lambda: scene.add_spot_light(t(), t(), e(), spot_size=min(x(), 3.0), radius=x()),
        "sun": lambda: scene.add_sun_light(t(), e(), angle=min(x(), 3.0)),
        "world": lambda: scene.set_world(e()),
    }
    call(calls[kind])


@FUZZ
@given(data=st.data(), scale=st.sampled_from([1.0, 1e-7, 1e5, 1e-30, 1e30]),
       shift=st.sampled_from([0.0, 1e5, -3e3, 1e20]))
def test_lighting_well_formed(data, scale, shift):
    scene = omis.Scene()
    mesh = floor(scene, scale, shift)
    for _ in range(data.draw(st.integers(1, 3))):
        valid_light(scene, data)
    call(scene.commit)
    techniques = data.draw(st.lists(st.sampled_from(TECHNIQUES), min_size=1, max_size=3,
                                    unique=True))
    counts = [data.draw(st.sampled_from([1, 2, 4])) for _ in techniques]
    strategy = data.draw(st.sampled_from(STRATEGIES))
    points = np.array([[0.2, 0.1, 0.0], [-0.7, 0.9, 0.0]]) * scale + shift
    normals = np.array(data.draw(st.sampled_from([[0, 0, 1.0], [0, 0, 1e-300], [1e300, 0, 1e300]])))
    out = call(omis.direct_lighting, scene, points, np.array([normals] * 2), techniques, counts,
               strategy=strategy, rounds=2)
    if out is not None:
        no_nan(*out)
    result = call(omis.bake_vertices, scene, mesh if mesh is not None else 0,
                  techniques=techniques, counts=counts, samples=4 * sum(counts),
                  strategy=strategy)
    if result is not None:
        no_nan(result.value, result.noise)
