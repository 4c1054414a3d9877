"""omis.Scene and omis.direct_lighting (SPEC §3, §4, §6): errors, exact answers, control.

Exact answers come from formulas written here, independently of the core: Lambert's
polygon formula (SPEC §5, clipped to the horizon), a disk seen on its axis, point and
sun lights. Estimates must lie within 4 standard errors — the square root of the
variance direct_lighting reports — of them; seeds are fixed, so runs are reproducible.
"""
import _thread
import math
import threading
import time

import numpy as np
import pytest

import omis

K_SIGMA = 4.0

# A 1 × 0.5 m rectangle 1 m above the floor, emitting downwards (cross(U, V) = −z).
CORNER = np.array([-0.5, -0.25, 1.0])
EDGE_U = np.array([0.0, 0.5, 0.0])
EDGE_V = np.array([1.0, 0.0, 0.0])
RADIANCE = np.array([1.0, 2.0, 0.5])
RECT = np.array([CORNER, CORNER + EDGE_U, CORNER + EDGE_U + EDGE_V, CORNER + EDGE_V])


def lambert(x, n, polygon):
    """E/L at x (unit normal n) from a polygon of unit radiance (SPEC §5)."""
    n = np.asarray(n, float) / np.linalg.norm(n)
    rel = np.asarray(polygon, float) - np.asarray(x, float)
    clipped = []  # the polygon's part above the horizon (Sutherland–Hodgman)
    for i in range(len(rel)):
        a, b = rel[i], rel[(i + 1) % len(rel)]
        da, db = n @ a, n @ b
        if da >= 0:
            clipped.append(a)
        if (da >= 0) != (db >= 0):
            clipped.append(a + da / (da - db) * (b - a))
    if len(clipped) < 3:
        return 0.0
    u = np.array(clipped) / np.linalg.norm(clipped, axis=1)[:, None]
    total = 0.0
    for e in range(len(u)):
        a, b = u[e], u[(e + 1) % len(u)]
        c = np.cross(a, b)
        s = np.linalg.norm(c)
        if s > 0:
            total += math.atan2(s, a @ b) * (n @ c) / s
    return 0.5 * abs(total)


def assert_close(value, variance, expected, what=""):
    value, variance, expected = np.broadcast_arrays(value, variance, expected)
    assert np.all(variance >= 0), what
    tolerance = K_SIGMA * np.sqrt(variance) + 1e-9 * np.abs(expected) + 1e-12
    bad = np.abs(value - expected) > tolerance
    assert not bad.any(), f"{what}: {value[bad]} vs {expected[bad]} ± {tolerance[bad]}"


def rect_scene(**kw):
    scene = omis.Scene()
    assert scene.add_rect_light(CORNER, EDGE_U, EDGE_V, RADIANCE, **kw) == 0
    scene.commit()
    return scene


# Receivers: under the light, beside it, far off, tilted, and one whose horizon
# cuts the light in two.
POINTS = np.array([[0, 0, 0], [0.3, -0.2, 0], [1.5, 0.5, 0], [0.1, 0.1, 0.2], [0, 0, 0.5]], float)
NORMALS = np.array([[0, 0, 1], [0, 0, 1], [0, 0, 1], [0.3, 0, 1], [1, 0, 0.3]], float)


def expected_rect(points=POINTS, normals=NORMALS, polygon=RECT):
    e = np.array([lambert(x, n, polygon) for x, n in zip(points, normals)])
    return e[:, None] * RADIANCE[None, :] / math.pi


# ---- exact answers ---------------------------------------------------------------

@pytest.mark.parametrize(
    "techniques, samples, strategy",
    [
        (["bsdf", "uniform/solid-angle"], [4, 4], "optimal-direct"),
        (["uniform/area", "unoccluded/parallel"], [4, 4], "balance"),
        ("power/solid-angle, bsdf", [6, 2], "optimal-progressive"),
        (["bsdf"], [8], "power"),
        (None, None, "optimal-direct"),
    ],
)
def test_rect_light_matches_lambert(techniques, samples, strategy):
    scene = rect_scene()
    value, variance = omis.direct_lighting(scene, POINTS, NORMALS, techniques, samples,
                                           rounds=16, strategy=strategy, seed=11)
    assert value.shape == (len(POINTS), 3) and value.dtype == np.float64
    assert variance.shape == value.shape
    assert_close(value, variance, expected_rect(), f"{techniques} {strategy}")
    assert value[4].min() > 0  # the half-visible light still lights the tilted receiver


@pytest.mark.parametrize("strategy", ["optimal-direct", "optimal-progressive"])
def test_rare_event_share_is_restored_far_from_the_light(strategy):
    # The far receiver (1.5, 0.5, 0) with power/solid-angle + bsdf [6, 2]: the
    # bsdf technique seldom hits the light, so the balance estimate misses
    # that share alike in nearly every round (rms error 3.2 of its reported σ
    # over seeds 11..110: its variance misses it too). The optimal strategies'
    # correction restores it in every half of the sequence alike; it must be
    # kept, not dropped by the level test or a fallback to balance. Then the
    # errors over 20 seeds have an rms of at most 1.5 reported σ: for honest σ
    # it is about 1 (± 0.16 for 20 normal draws, so 1.5 is 3 SE above), while
    # a dropped correction leaves balance's ~3.2. Measured: 0.07 direct,
    # 0.03 progressive.
    scene = rect_scene()
    point, normal = POINTS[2:3], NORMALS[2:3]
    expected = expected_rect(point, normal)[0]
    z = []
    for seed in range(11, 31):
        value, variance = omis.direct_lighting(scene, point, normal, "power/solid-angle, bsdf",
                                               [6, 2], rounds=16, strategy=strategy, seed=seed)
        z.append((value[0] - expected) / np.sqrt(variance[0]))
    rms = float(np.sqrt(np.mean(np.square(z))))
    assert rms <= 1.5, f"{strategy}: rms error {rms:.2f} reported σ"


def test_normals_need_not_be_unit_and_float32_is_accepted():
    scene = rect_scene()
    a = omis.direct_lighting(scene, POINTS, NORMALS, seed=3)
    b = omis.direct_lighting(scene, POINTS.astype(np.float32), 7.0 * NORMALS, seed=3)
    np.testing.assert_allclose(a[0], b[0], rtol=1e-6)


def test_two_sided_and_back_side():
    scene = rect_scene(two_sided=True)
    above = np.array([[0.0, 0.0, 2.0]])
    down = np.array([[0.0, 0.0, -1.0]])
    value, variance = omis.direct_lighting(scene, above, down, rounds=16)
    assert_close(value, variance, expected_rect(above, down))
    one_sided = rect_scene()
    value, variance = omis.direct_lighting(one_sided, above, down, rounds=4)
    assert np.all(value == 0)


def test_emissive_mesh_from_strided_float32_vertices():
    # The rectangle as an emissive two-triangle mesh; vertices are a strided view.
    padded = np.zeros((4, 5), np.float32)
    padded[:, :3] = RECT
    vertices = padded[:, :3]
    assert not vertices.flags.c_contiguous
    scene = omis.Scene()
    assert scene.add_mesh(vertices, np.array([[0, 1, 2], [0, 2, 3]], np.int64),
                          emission=RADIANCE) == 0
    scene.commit()
    value, variance = omis.direct_lighting(scene, POINTS[:4], NORMALS[:4],
                                           ["uniform/solid-angle", "bsdf"], [4, 4], rounds=16)
    assert_close(value, variance, expected_rect(POINTS[:4], NORMALS[:4], RECT.astype(np.float32)))


def test_half_occluded_light_and_cast_shadow_flag():
    # An opaque sheet at z = 0.9 over x < 0: from a floor point p, the visible part
    # of the light is x > p_x (1 − 1/0.9), itself a rectangle.
    sheet = np.array([[-3, -3, 0.9], [0, -3, 0.9], [0, 3, 0.9], [-3, 3, 0.9]], float)
    points = np.array([[0.0, 0.0, 0.0], [0.2, 0.1, 0.0], [-0.1, 0.0, 0.0]])
    normals = np.tile([0.0, 0.0, 1.0], (3, 1))
    expected = []
    for p in points:
        x0 = max(CORNER[0], p[0] * (1 - 1 / 0.9))
        visible = np.array([[x0, -0.25, 1], [x0, 0.25, 1], [0.5, 0.25, 1], [0.5, -0.25, 1]])
        expected.append(lambert(p, [0, 0, 1], visible))
    expected = np.array(expected)[:, None] * RADIANCE / math.pi

    for cast_shadow in (True, False):
        scene = omis.Scene()
        scene.add_mesh(sheet, [[0, 1, 2], [0, 2, 3]])
        light = scene.add_rect_light(CORNER, EDGE_U, EDGE_V, RADIANCE)
        scene.set_light_flags(light, cast_shadow=cast_shadow)
        scene.commit()
        value, variance, stats = omis.direct_lighting(
            scene, points, normals, ["unoccluded/solid-angle", "bsdf"], [4, 4], rounds=32,
            seed=5, return_stats=True)
        assert_close(value, variance, expected if cast_shadow else expected_rect(points, normals),
                     f"cast_shadow={cast_shadow}")
        assert stats["rays_traced"] > 0 if cast_shadow else True


def test_disk_light_on_its_axis():
    # E = L π r² / (h² + r²) on the axis of a disk facing the receiver.
    h, r, L = 1.5, 0.4, 3.0
    x = np.array([[0.0, 0.0, 0.0]])
    n = np.array([[0.0, 0.0, 1.0]])
    facing = omis.Scene()
    facing.add_disk_light([0, 0, h], [0, 0, -1], r, L)  # grey radiance
    facing.commit()
    value, variance = omis.direct_lighting(facing, x, n, ["uniform/area", "bsdf"], [4, 4],
                                           rounds=16)
    assert_close(value, variance, np.full((1, 3), L * r * r / (h * h + r * r)))
    away = omis.Scene()
    away.add_disk_light([0, 0, h], [0, 0, 1], r, L)  # emits upwards: its back faces x
    away.commit()
    value, _ = omis.direct_lighting(away, x, n, ["uniform/area", "bsdf"], [4, 4], rounds=4)
    assert np.all(value == 0)


def test_delta_lights_are_exact():
    # Point: E = I cos θ / d²; sun: E = S cos θ. One shadow ray each, no MIS.
    scene = omis.Scene()
    scene.add_point_light([1.0, 0.0, 2.0], [10.0, 20.0, 30.0])
    scene.add_sun_light([0.0, -0.6, -0.8], 2.0)  # travelling down and along −y
    scene.commit()
    x = np.array([[0.0, 0.0, 0.0]])
    n = np.array([[0.0, 0.0, 1.0]])
    value, variance, stats = omis.direct_lighting(scene, x, n, return_stats=True)
    d2 = 1.0 + 4.0
    point = np.array([10.0, 20.0, 30.0]) * (2.0 / math.sqrt(d2)) / d2
    sun = 2.0 * 0.8
    np.testing.assert_allclose(value[0], (point + sun) / math.pi, rtol=1e-12)
    assert np.all(variance == 0)
    assert stats["mis_systems"] == 0 and stats["rays_traced"] == 0


def test_no_points():
    value, variance = omis.direct_lighting(rect_scene(), np.zeros((0, 3)), np.zeros((0, 3)))
    assert value.shape == (0, 3) and variance.shape == (0, 3)


# ---- determinism, stats, plan ---------------------------------------------------

def test_deterministic_for_a_seed():
    scene = rect_scene()
    run = lambda seed: omis.direct_lighting(scene, POINTS, NORMALS, ["bsdf", "power/area"],
                                            [3, 3], rounds=4, seed=seed)
    a, b, c = run(42), run(42), run(43)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])
    big = run(2**64 - 1)  # the whole uint64 range is a valid seed
    assert np.isfinite(big[0]).all()


def test_streams_trade_error_for_a_measured_variance():
    # 256 copies of one point (each its own randomization): their spread is
    # the true error. With one sequence the reported variance is the
    # independent-draw formula, which must not under-state it; with four
    # streams it is their spread (3 degrees of freedom per copy), whose RMS
    # over 256 copies is within a few % of the truth, so [0.8, 1.25] holds
    # unless the estimate is wrong.
    scene = omis.Scene()
    scene.add_rect_light((-0.5, -0.5, 1.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    scene.add_rect_light((0.2, -0.5, 0.4), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (3.0, 3.0, 3.0))
    scene.commit()
    points = np.tile([0.3, 0.1, 0.0], (256, 1))
    normals = np.tile([0.0, 0.0, 1.0], (256, 1))
    for streams in (1, 4):
        value, variance = omis.direct_lighting(scene, points, normals, "bsdf,unoccluded/area",
                                               [1, 1], rounds=64, strategy="balance", seed=3,
                                               streams=streams)
        true_sd = value[:, 1].std()
        reported = math.sqrt(variance[:, 1].mean())
        assert reported >= 0.8 * true_sd, (streams, reported, true_sd)
        if streams > 1:
            assert reported <= 1.25 * true_sd, (streams, reported, true_sd)


def test_heuristic_options_reach_the_native_job():
    # The power heuristic with beta = 1 and the cutoff heuristic with cutoff = 0 are
    # the balance heuristic (SPEC §1); another beta is not.
    scene = rect_scene()
    run = lambda **kw: omis.direct_lighting(scene, POINTS, NORMALS, ["bsdf", "uniform/area"],
                                            [2, 2], rounds=4, seed=5, **kw)[0]
    balance = run(strategy="balance")
    np.testing.assert_allclose(run(strategy="power", beta=1.0), balance, rtol=1e-12)
    np.testing.assert_allclose(run(strategy="cutoff", cutoff=0.0), balance, rtol=1e-12)
    assert not np.allclose(run(strategy="power", beta=3.0), balance, rtol=1e-6)


def test_stats_and_effect_plan():
    scene = rect_scene()
    techniques, samples = ["bsdf", "uniform/solid-angle"], [2, 3]
    value, variance, stats = omis.direct_lighting(scene, POINTS, NORMALS, techniques, samples,
                                                  rounds=4, return_stats=True)
    assert set(stats) == {"points", "samples", "rays_traced", "mis_systems",
                          "pdf_evaluations", "seconds", "plan"}
    assert stats["points"] == len(POINTS)
    assert stats["samples"] == len(POINTS) * 4 * 5
    assert stats["mis_systems"] == len(POINTS)
    assert stats["rays_traced"] == 0  # no geometry: nothing to occlude
    assert stats["pdf_evaluations"] > 0
    assert stats["seconds"] >= 0
    plan = scene.effect_plan(techniques, samples)
    assert stats["plan"] == plan
    assert "bsdf" in plan and "uniform/solid-angle" in plan and "shadow rays: no" in plan
    default = scene.effect_plan()
    assert isinstance(default, str) and "techniques" in default
    assert scene.effect_plan("bsdf,uniform/solid-angle", [2, 3]) == plan


def uv_sphere(centre, radius, stacks, slices):
    """A closed UV sphere: (vertices, triangles) with outward winding."""
    theta = np.pi * np.arange(1, stacks) / stacks
    phi = 2 * np.pi * np.arange(slices) / slices
    ring = np.stack([np.outer(np.sin(theta), np.cos(phi)), np.outer(np.sin(theta), np.sin(phi)),
                     np.repeat(np.cos(theta)[:, None], slices, 1)], -1).reshape(-1, 3)
    vertices = np.concatenate([[[0, 0, 1]], ring, [[0, 0, -1]]]) * radius + centre
    bottom = len(vertices) - 1
    tris = []
    for j in range(slices):
        k = (j + 1) % slices
        tris += [[0, 1 + j, 1 + k], [bottom, 1 + (stacks - 2) * slices + k,
                                     1 + (stacks - 2) * slices + j]]
        for i in range(stacks - 2):
            a, b = 1 + i * slices, 1 + (i + 1) * slices
            tris += [[a + j, b + j, b + k], [a + j, b + k, a + k]]
    return vertices, np.array(tris, np.int64)


@pytest.mark.parametrize("mesh_lights", [True, False])
def test_emissive_sphere_as_one_mesh_light_or_per_triangle(mesh_lights):
    # A UV sphere of 3,968 triangles (radius 0.4 m at 1.2 m) over points on the
    # floor and a tilted one: drawn as one mesh light (toward its bounding
    # sphere) or as a light per triangle, both estimate the inscribed
    # polyhedron's E/π. Its value lies below the true sphere's L·sin²α·cosθ
    # (fully above the horizon) by the polyhedron's missing solid angle, under
    # 1 % at 32 × 64 segments: the bound is 4σ + 1.5 %.
    vertices, tris = uv_sphere(np.array([0.0, 0.0, 1.2]), 0.4, 32, 64)
    scene = omis.Scene()
    scene.add_mesh((QUAD - [0.5, 0.5, 0]) * 4, TRIS)  # a floor: an occluder
    scene.add_mesh(vertices, tris, emission=RADIANCE)
    scene.set_mesh_lights(mesh_lights)
    scene.commit()
    plan = scene.effect_plan()
    assert ("mesh×1" in plan) == mesh_lights and ("triangle×" in plan) != mesh_lights
    points = np.array([[0, 0, 0], [0.5, 0.2, 0], [1.5, -0.5, 0], [0.2, 0, 0.3]], float)
    normals = np.array([[0, 0, 1], [0, 0, 1], [0, 0, 1], [0.2, 0, 1]], float)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    value, variance = omis.direct_lighting(scene, points, normals, rounds=64)
    d = np.array([0.0, 0.0, 1.2]) - points
    dist = np.linalg.norm(d, axis=1)
    sphere = (0.4 / dist) ** 2 * np.sum(normals * d, axis=1) / dist
    expected = sphere[:, None] * RADIANCE[None, :]
    bound = K_SIGMA * np.sqrt(variance) + 0.015 * expected
    assert np.all(value <= expected + bound) and np.all(value >= expected - bound)
    with pytest.raises(RuntimeError, match="committed"):
        scene.set_mesh_lights(not mesh_lights)


# ---- progress, cancellation, Ctrl-C -----------------------------------------------

def big_job(scene, **kw):
    rng = np.random.default_rng(0)
    points = np.zeros((60000, 3))
    points[:, :2] = rng.uniform(-1, 1, (60000, 2))
    normals = np.tile([0.0, 0.0, 1.0], (60000, 1))
    return omis.direct_lighting(scene, points, normals, ["bsdf", "uniform/area"], [8, 8],
                                rounds=8, **kw)


def test_progress_is_called():
    scene = rect_scene()
    fractions = []
    value, _ = omis.direct_lighting(scene, POINTS, NORMALS, progress=fractions.append)
    assert fractions and fractions[-1] == 1.0
    assert all(0 <= f <= 1 for f in fractions)


def test_progress_false_cancels():
    scene = rect_scene()
    calls = []

    def stop(fraction):
        calls.append(fraction)
        return False

    start = time.perf_counter()
    with pytest.raises(omis.Cancelled):
        big_job(scene, progress=stop)
    assert len(calls) == 1  # not called again once cancelled
    assert issubclass(omis.Cancelled, RuntimeError)
    # A callable returning None (a logger, say) does not cancel.
    value, _ = omis.direct_lighting(scene, POINTS, NORMALS, progress=lambda f: None)
    assert time.perf_counter() - start < 60


def test_exception_in_progress_propagates():
    def boom(fraction):
        raise ZeroDivisionError("from progress")

    with pytest.raises(ZeroDivisionError, match="from progress"):
        big_job(rect_scene(), progress=boom)


def test_ctrl_c_interrupts_without_progress():
    scene = rect_scene()
    timer = threading.Timer(0.1, _thread.interrupt_main)  # as if SIGINT arrived
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            big_job(scene)
    finally:
        timer.cancel()


# ---- errors ---------------------------------------------------------------------

QUAD = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
TRIS = np.array([[0, 1, 2], [0, 2, 3]])


@pytest.mark.parametrize(
    "call, argument",
    [
        (lambda s: s.add_mesh(QUAD[:, :2], TRIS), "vertices"),
        (lambda s: s.add_mesh(QUAD.astype(np.int64), TRIS), "vertices"),
        (lambda s: s.add_mesh(np.where(QUAD == 1, np.nan, QUAD), TRIS), "vertices"),
        (lambda s: s.add_mesh(QUAD[:0], TRIS), "vertices"),
        (lambda s: s.add_mesh(QUAD, TRIS.astype(float)), "triangles"),
        (lambda s: s.add_mesh(QUAD, TRIS[:, :2]), "triangles"),
        (lambda s: s.add_mesh(QUAD, TRIS + 1), "triangles"),
        (lambda s: s.add_mesh(QUAD, TRIS - 1), "triangles"),
        (lambda s: s.add_mesh(QUAD, TRIS, normals=np.zeros((4, 3))), "normals"),
        (lambda s: s.add_mesh(QUAD, TRIS, normals=np.full((6, 3), np.inf)), "normals"),
        (lambda s: s.add_mesh(QUAD, TRIS, uvs=np.zeros((6, 3))), "uvs"),
        (lambda s: s.add_mesh(QUAD, TRIS, emission=[1, 2]), "emission"),
        (lambda s: s.add_mesh(QUAD, TRIS, emission=-1.0), "emission"),
        (lambda s: s.add_rect_light(CORNER, EDGE_U, 2 * EDGE_U, 1.0), "edge_u"),
        (lambda s: s.add_rect_light(CORNER, EDGE_U, [0, 0, 0], 1.0), "edge_u"),
        (lambda s: s.add_rect_light(CORNER[:2], EDGE_U, EDGE_V, 1.0), "corner"),
        (lambda s: s.add_rect_light(CORNER, EDGE_U, EDGE_V, [1, np.nan, 1]), "radiance"),
        (lambda s: s.add_rect_light(CORNER, EDGE_U, EDGE_V, "white"), "radiance"),
        (lambda s: s.add_rect_light(CORNER, EDGE_U, EDGE_V, 1.0, spread=0.0), "spread"),
        (lambda s: s.add_ellipse_light(CORNER, EDGE_U, EDGE_U, 1.0), "axis_u"),
        (lambda s: s.add_disk_light(CORNER, [0, 0, 0], 0.5, 1.0), "normal"),
        (lambda s: s.add_disk_light(CORNER, [0, 0, 1], 0.0, 1.0), "radius"),
        (lambda s: s.add_point_light([0, 0, 1], 1.0, radius=-1.0), "radius"),
        (lambda s: s.add_point_light([0, 0, 1], [-1, 1, 1]), "intensity"),
        (lambda s: s.add_spot_light([0, 0, 1], [0, 0, -1], 1.0, spot_size=0.0), "spot_size"),
        (lambda s: s.add_spot_light([0, 0, 1], [0, 0, -1], 1.0, 1.0, spot_blend=2.0), "spot_blend"),
        (lambda s: s.add_sun_light([0, 0, 0], 1.0), "direction"),
        (lambda s: s.add_sun_light([0, 0, -1], 1.0, angle=-0.1), "angle"),
        (lambda s: s.set_world([1, 1]), "radiance"),
        (lambda s: s.set_light_flags(7), "light"),
        (lambda s: s.set_light_flags(-1), "light"),
    ],
)
def test_bad_scene_input_names_the_argument(call, argument):
    scene = omis.Scene()
    with pytest.raises(ValueError, match=f"^{argument}:"):
        call(scene)
    # A failed add leaves no trace: ids still start at 0.
    assert scene.add_rect_light(CORNER, EDGE_U, EDGE_V, 1.0) == 0


@pytest.mark.parametrize(
    "kw, argument",
    [
        (dict(points=POINTS[:, :2]), "points"),
        (dict(points=POINTS.astype(int)), "points"),
        (dict(normals=NORMALS[:3]), "normals"),
        (dict(points=np.where(np.arange(5)[:, None] == 2, np.nan, POINTS)), "points"),
        (dict(normals=np.where(np.arange(5)[:, None] == 3, 0.0, NORMALS)), "normals"),
        (dict(techniques=["bsdf", "uniform/areal"], samples=[1, 1]), "techniques"),
        (dict(techniques="bsdf,,uniform/area", samples=[1, 1]), "techniques"),
        (dict(techniques=["bsdf", "bsdf"], samples=[1, 1]), "techniques"),
        (dict(techniques=["bsdf,uniform/area"], samples=[1]), "techniques"),
        (dict(techniques=[], samples=[]), "techniques"),
        (dict(techniques=["bsdf", "uniform/area"], samples=[1]), "samples"),
        (dict(techniques="bsdf, uniform/area", samples=[1, 1, 1]), "samples"),
        (dict(techniques=["bsdf", "uniform/area"]), "samples"),
        (dict(samples=[1, 1]), "samples"),
        (dict(techniques=["bsdf"], samples=[-1]), "samples"),
        (dict(techniques=["bsdf"], samples=[1.5]), "samples"),
        (dict(rounds=0), "rounds"),
        (dict(strategy="optimal"), "strategy"),
        (dict(seed=-1), "seed"),
        (dict(seed=2**64), "seed"),
        (dict(beta=0.0, strategy="power"), "beta"),
        (dict(cutoff=2.0, strategy="cutoff"), "cutoff"),
        (dict(streams=0), "streams"),
        (dict(streams=5), "streams"),
        (dict(progress=3), "progress"),
    ],
)
def test_bad_lighting_input_names_the_argument(kw, argument):
    args = dict(points=POINTS, normals=NORMALS)
    args.update(kw)
    with pytest.raises(ValueError, match=f"^{argument}:"):
        omis.direct_lighting(rect_scene(), **args)


def test_order_errors():
    scene = omis.Scene()
    scene.add_rect_light(CORNER, EDGE_U, EDGE_V, RADIANCE)
    with pytest.raises(RuntimeError, match="commit"):
        omis.direct_lighting(scene, POINTS, NORMALS)
    with pytest.raises(RuntimeError, match="commit"):
        scene.effect_plan()
    scene.commit()
    scene.commit()  # a second commit does nothing
    with pytest.raises(RuntimeError, match="committed"):
        scene.add_point_light([0, 0, 1], 1.0)
    with pytest.raises(RuntimeError, match="committed"):
        scene.add_mesh(QUAD, TRIS)
    with pytest.raises(RuntimeError, match="committed"):
        scene.set_light_flags(0, cast_shadow=False)
    with pytest.raises(ValueError, match="^techniques:"):
        scene.effect_plan(["nope"], [1])
    with pytest.raises(TypeError):
        omis.direct_lighting("not a scene", POINTS, NORMALS)
