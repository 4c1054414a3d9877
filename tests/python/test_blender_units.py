"""Blender 3.4 / Cycles light units (SPEC §4), checked against the values
measured on this Blender and against closed-form irradiance (SPEC §5)."""
import math

import numpy as np
import pytest

from omis import blender_units as bu

WHITE = (1.0, 1.0, 1.0)


def polygon_irradiance(L, x, n, vertices):
    """Lambert: E = (L/2) Σ θ_e n·(v_e × v_e+1)/|v_e × v_e+1| (polygon above the horizon)."""
    v = [np.asarray(p, float) - x for p in vertices]
    v = [p / np.linalg.norm(p) for p in v]
    total = 0.0
    for a, b in zip(v, v[1:] + v[:1]):
        c = np.cross(a, b)
        theta = math.atan2(np.linalg.norm(c), float(np.dot(a, b)))
        total += theta * float(np.dot(n, c / np.linalg.norm(c)))
    return abs(0.5 * L * total)


# ---------------------------------------------------------------- SPEC §4 values

def test_point_light_measured_value():
    p = bu.point_light(1000.0, WHITE)
    d = 1.0
    e_over_pi = p.intensity[0] / d**2 / math.pi
    assert e_over_pi == pytest.approx(25.33, abs=0.005)
    assert p.disk_radiance is None and p.radius == 0.0


def test_area_light_measured_value():
    a = bu.area_light(1000.0, WHITE, "SQUARE", 0.1)
    assert a.area == pytest.approx(0.01)
    assert a.radiance[0] == pytest.approx(1000.0 / (4 * 0.01))
    h = 0.05
    square = [(-h, -h, 1.0), (h, -h, 1.0), (h, h, 1.0), (-h, h, 1.0)]
    e = polygon_irradiance(a.radiance[0], np.zeros(3), np.array([0.0, 0.0, 1.0]), square)
    assert e / math.pi == pytest.approx(79.3, abs=0.05)


def test_sun_measured_value():
    s = bu.sun_light(math.pi, WHITE)
    assert s.irradiance[0] / math.pi == pytest.approx(1.000, abs=1e-12)
    assert s.radiance_on_axis is None


# ---------------------------------------------------------------- spread

def test_spread_factor_is_one_at_pi():
    assert bu.area_spread_normalization(math.pi) == 1.0
    for theta in np.linspace(0.0, 1.5, 16):
        assert bu.area_spread_factor(float(theta), math.pi) == 1.0
    arr = bu.area_spread_factor(np.linspace(0.0, 1.5, 16), math.pi)
    assert np.all(arr == 1.0)
    assert bu.area_spread_factor(2.0, math.pi) == 0.0  # behind the light


@pytest.mark.parametrize("spread", [0.01, 0.3, 1.0, 2.0, 3.0])
def test_spread_factor_decreases_with_theta(spread):
    thetas = np.linspace(0.0, 0.5 * spread, 50)
    f = np.array([bu.area_spread_factor(float(t), spread) for t in thetas])
    assert np.all(np.diff(f) < 0)
    assert f[-1] == pytest.approx(0.0, abs=1e-9)  # cut off at the half angle s/2
    assert bu.area_spread_factor(0.5 * spread + 1e-3, spread) == 0.0
    # Array and scalar forms agree.
    np.testing.assert_allclose(bu.area_spread_factor(thetas, spread), f, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("spread", [0.05, 0.5, 1.5, 2.5, 3.1])
def test_spread_matches_spec_formula_and_preserves_power(spread):
    a = 0.5 * (math.pi - spread)
    spec = 2.0 / (2.0 + (2.0 * a - math.pi) * math.tan(a))
    assert bu.area_spread_normalization(spread) == pytest.approx(spec, rel=1e-9)
    # ∫ factor(θ) cosθ dω over the hemisphere = π, like a Lambertian emitter.
    theta = np.linspace(0.0, 0.5 * math.pi, 200001)
    integrand = bu.area_spread_factor(theta, spread) * np.cos(theta) * np.sin(theta)
    power = 2.0 * math.pi * np.trapz(integrand, theta)
    assert power == pytest.approx(math.pi, rel=2e-3)


def test_spread_small_angle_series_is_continuous():
    below = bu.area_spread_normalization(2 * (1e-2 - 1e-9))
    above = bu.area_spread_normalization(2 * (1e-2 + 1e-9))
    assert below == pytest.approx(above, rel=1e-6)
    # 1/(b²/3) for tiny b: no cancellation blow-up.
    b = 1e-6
    assert bu.area_spread_normalization(2 * b) == pytest.approx(3.0 / b**2, rel=1e-6)


# ---------------------------------------------------------------- shapes and lights

def test_area_shapes():
    assert bu.area_light_area("SQUARE", 2.0) == 4.0
    assert bu.area_light_area("RECTANGLE", 2.0, 3.0) == 6.0
    assert bu.area_light_area("DISK", 2.0) == pytest.approx(math.pi)
    assert bu.area_light_area("ELLIPSE", 2.0, 4.0) == pytest.approx(2.0 * math.pi)
    a = bu.area_light(100.0, (1.0, 0.5, 0.0), "DISK", 1.0, spread=1.0)
    assert a.radiance == pytest.approx((100 / math.pi, 50 / math.pi, 0.0))
    assert a.spread_normalization == bu.area_spread_normalization(1.0)


def test_point_light_disk_matches_intensity_far_away():
    p = bu.point_light(500.0, (1.0, 2.0, 3.0), radius=0.1)
    assert p.intensity == pytest.approx(tuple(500 * c / (4 * math.pi) for c in (1, 2, 3)))
    assert p.disk_area == pytest.approx(math.pi * 0.01)
    for k in range(3):
        assert p.disk_radiance[k] * p.disk_area == pytest.approx(p.intensity[k])


def test_spot_cone_and_attenuation():
    size, blend = math.radians(60.0), 0.2
    half, cos_half, smooth = bu.spot_cone(size, blend)
    assert half == pytest.approx(math.radians(30.0))
    assert cos_half == pytest.approx(math.cos(math.radians(30.0)))
    assert smooth == pytest.approx((1 - cos_half) * blend)
    att = lambda c, **k: bu.spot_attenuation(c, size, blend, **k)
    assert att(math.cos(math.radians(31.0))) == 0.0
    assert att(cos_half) == 0.0
    assert att(1.0) == 1.0
    c_in = math.cos(math.radians(10.0))  # beyond the blend band
    assert c_in - cos_half > smooth
    assert att(c_in) == pytest.approx(c_in)
    assert att(c_in, cycles_cosine=False) == 1.0
    c_mid = cos_half + 0.5 * smooth  # smoothstep(0.5) = 0.5
    assert att(c_mid, cycles_cosine=False) == pytest.approx(0.5)
    assert att(c_mid) == pytest.approx(0.5 * c_mid)
    cs = np.linspace(cos_half - 0.1, 1.0, 101)
    np.testing.assert_allclose(att(cs), [att(float(c)) for c in cs], rtol=1e-12)
    assert np.all(np.diff(att(cs, cycles_cosine=False)) >= 0)
    # Without blend the edge is sharp.
    assert bu.spot_attenuation(cos_half + 1e-9, size, 0.0, cycles_cosine=False) == 1.0
    s = bu.spot_light(1000.0, WHITE, size, blend)
    assert s.intensity[0] == pytest.approx(1000 / (4 * math.pi))  # not renormalised
    assert s.half_angle == half and s.smooth_width == smooth


@pytest.mark.parametrize("angle_deg", [0.526, 5.0, 30.0, 60.0])
def test_sun_with_angle(angle_deg):
    s = bu.sun_light(2.0, (1.0, 0.5, 0.25), math.radians(angle_deg))
    alpha = math.radians(angle_deg) / 2
    assert s.half_angle == pytest.approx(alpha)
    assert s.solid_angle == pytest.approx(2 * math.pi * (1 - math.cos(alpha)))
    # ∫ L(θ') cosθ' dω over the cone (facing surface) equals normal_irradiance.
    th = np.linspace(0.0, alpha, 20001)
    L = np.array([bu.sun_radiance(math.cos(t), 2.0, (1.0, 0.5, 0.25),
                                  math.radians(angle_deg))[0] for t in th[:-1]] + [0.0])
    L[-1] = L[-2]
    e = 2 * math.pi * np.trapz(L * np.cos(th) * np.sin(th), th)
    assert e == pytest.approx(s.normal_irradiance[0], rel=1e-6)
    assert s.irradiance == (2.0, 1.0, 0.5)
    assert bu.sun_radiance(math.cos(alpha * 1.01), 2.0, WHITE, math.radians(angle_deg)) == (0, 0, 0)


def test_sun_60_degrees_measured_on_blender_3_4():
    # Cycles 3.4 DIFFUSE/DIRECT bake, plane facing a sun of S = π, angle 60°: 0.928.
    s = bu.sun_light(math.pi, WHITE, math.radians(60.0))
    assert s.normal_irradiance[0] / math.pi == pytest.approx(0.928, abs=0.002)


def test_spot_cosine_measured_on_blender_3_4():
    # Cycles 3.4 bake, spot P=1000 W at 1 m above a plane, spot_size 120°, blend 0:
    # E/π at x = 1.031 m was 5.947 (pixel centre), which needs the cosine to the axis.
    x = 1.03125
    d2 = x * x + 1.0
    c = 1.0 / math.sqrt(d2)
    s = bu.spot_light(1000.0, WHITE, math.radians(120.0), 0.0)
    e = s.intensity[0] * bu.spot_attenuation(c, math.radians(120.0), 0.0) * c / d2
    assert e / math.pi == pytest.approx(5.947, rel=2e-3)


def test_emission_and_world():
    assert bu.mesh_emission(3.0, (1.0, 0.5, 0.0)) == (3.0, 1.5, 0.0)
    assert bu.mesh_emission(1.0, (0.2, 0.3, 0.4, 1.0)) == (0.2, 0.3, 0.4)  # RGBA ok
    assert bu.world_background((0.5, 0.5, 0.5), 2.0) == (1.0, 1.0, 1.0)


# ---------------------------------------------------------------- validation

@pytest.mark.parametrize("call, name", [
    (lambda: bu.point_light(-1.0, WHITE), "energy"),
    (lambda: bu.point_light(float("nan"), WHITE), "energy"),
    (lambda: bu.point_light(1.0, (1.0, float("nan"), 0.0)), "color[1]"),
    (lambda: bu.point_light(1.0, (1.0, 1.0)), "color"),
    (lambda: bu.point_light(1.0, WHITE, radius=-0.1), "radius"),
    (lambda: bu.area_light(1.0, WHITE, "SQUARE", 0.0), "size"),
    (lambda: bu.area_light(1.0, WHITE, "RECTANGLE", 1.0, 0.0), "size_y"),
    (lambda: bu.area_light(1.0, WHITE, "RECTANGLE", 1.0), "size_y"),
    (lambda: bu.area_light(1.0, WHITE, "TRIANGLE", 1.0), "shape"),
    (lambda: bu.area_light(1.0, WHITE, "SQUARE", 1.0, spread=0.0), "spread"),
    (lambda: bu.area_light(1.0, WHITE, "SQUARE", 1.0, spread=4.0), "spread"),
    (lambda: bu.area_light(-5.0, WHITE, "SQUARE", 1.0), "energy"),
    (lambda: bu.area_light(1.0, (-1.0, 0.0, 0.0), "SQUARE", 1.0), "color[0]"),
    (lambda: bu.spot_light(1.0, WHITE, 0.0, 0.1), "spot_size"),
    (lambda: bu.spot_light(1.0, WHITE, 1.0, 1.5), "spot_blend"),
    (lambda: bu.spot_light(1.0, WHITE, 1.0, -0.1), "spot_blend"),
    (lambda: bu.sun_light(-1.0, WHITE), "strength"),
    (lambda: bu.sun_light(1.0, WHITE, float("inf")), "angle"),
    (lambda: bu.sun_light(1.0, WHITE, 4.0), "angle"),
    (lambda: bu.mesh_emission(float("nan"), WHITE), "strength"),
    (lambda: bu.world_background(WHITE, -2.0), "strength"),
    (lambda: bu.world_background("white", 1.0), "color"),
])
def test_invalid_arguments_name_the_argument(call, name):
    with pytest.raises(ValueError) as err:
        call()
    assert name in str(err.value)


def test_blenders_float32_pi_is_pi():
    # Blender stores the default spread and the widest spot as float32 π.
    pi32 = float(np.float32(math.pi))
    assert pi32 > math.pi
    assert bu.area_spread_normalization(pi32) == bu.area_spread_normalization(math.pi)
    assert bu.spot_cone(pi32, 0.1) == bu.spot_cone(math.pi, 0.1)
    with pytest.raises(ValueError, match="spread"):
        bu.area_spread_normalization(3.2)
