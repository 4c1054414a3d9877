"""Blender 3.4 / Cycles light settings -> omis physical units (SPEC §4).

The one place the Blender add-on converts light settings. Every function takes
plain numbers (never bpy objects), so it is testable without Blender, and
returns a small named tuple of floats / RGB tuples in SI units:

    radiance    W / (m² sr)        (area lights, light disks, mesh emission, world)
    intensity   W / sr             (point and spot lights of radius 0)
    irradiance  W / m²             (sun, on a surface facing it)
    area        m²
    angles      radians

The baked quantity is E/π (SPEC §3); at 1 m, facing, Cycles 3.4 gives
point P=1000 W -> 25.33, area P=1000 W 0.1 m square -> 79.3, sun S=π -> 1.000.

Blender 3.4 conventions (Blender 4.0 changed area lights to P/(πA); this module
follows 3.4). Where SPEC §4 is terse, the reading taken here is written in the
function's docstring; the Cycles source for the 3.x series was the reference.
"""

import math
from typing import NamedTuple, Optional, Sequence, Tuple

RGB = Tuple[float, float, float]

AREA_SHAPES = ("SQUARE", "RECTANGLE", "DISK", "ELLIPSE")

__all__ = [
    "RGB",
    "AREA_SHAPES",
    "AreaLightUnits",
    "PointLightUnits",
    "SpotLightUnits",
    "SunLightUnits",
    "area_light_area",
    "area_light",
    "area_spread_normalization",
    "area_spread_factor",
    "point_light",
    "spot_cone",
    "spot_attenuation",
    "spot_light",
    "sun_light",
    "sun_radiance",
    "mesh_emission",
    "world_background",
]


# --------------------------------------------------------------------------
# Argument checks: every error names the argument.


# Blender stores angles as float32: its π (the default spread, the largest spot
# size) is 3.1415927410125732, a little above math.pi. Accept it as π.
_PI_FLOAT32 = 3.1415927410125732 * (1.0 + 1e-7)


def _number(name: str, value, *, positive: bool = False) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if math.isnan(x) or math.isinf(x):
        raise ValueError(f"{name} must be finite, got {x}")
    if x < 0.0:
        raise ValueError(f"{name} must not be negative, got {x}")
    if positive and x == 0.0:
        raise ValueError(f"{name} must be positive, got {x}")
    return x


def _color(name: str, value: Sequence[float]) -> RGB:
    try:
        parts = [value[i] for i in range(len(value))]
    except TypeError:
        raise ValueError(f"{name} must be an RGB triple, got {value!r}") from None
    if len(parts) == 4:  # Blender colours may carry alpha; it has no radiometric meaning
        parts = parts[:3]
    if len(parts) != 3:
        raise ValueError(f"{name} must have 3 (RGB) components, got {len(parts)}")
    return tuple(_number(f"{name}[{i}]", c) for i, c in enumerate(parts))  # type: ignore


def _scale(rgb: RGB, s: float) -> RGB:
    return (rgb[0] * s, rgb[1] * s, rgb[2] * s)


# --------------------------------------------------------------------------
# Area lights


class AreaLightUnits(NamedTuple):
    radiance: RGB                 # W/(m² sr), one-sided, before the spread factor
    area: float                   # m²
    spread: float                 # rad, Blender's `spread` (π = plain Lambertian)
    spread_normalization: float   # 2/(2 + (2a − π) tan a), a = (π − spread)/2; 1 at π


def area_light_area(shape: str, size: float, size_y: Optional[float] = None) -> float:
    """Emitting area in m² of a Blender area light.

    SQUARE: size²; RECTANGLE: size·size_y; DISK: (π/4)·size² (size is the
    diameter); ELLIPSE: (π/4)·size·size_y. size_y is ignored for SQUARE and DISK.
    """
    key = str(shape).upper()
    if key not in AREA_SHAPES:
        raise ValueError(f"shape must be one of {AREA_SHAPES}, got {shape!r}")
    sx = _number("size", size, positive=True)
    if key in ("RECTANGLE", "ELLIPSE"):
        if size_y is None:
            raise ValueError(f"size_y is required for shape {key}")
        sy = _number("size_y", size_y, positive=True)
    else:
        sy = sx
    area = sx * sy
    if key in ("DISK", "ELLIPSE"):
        area *= math.pi / 4.0
    if not area > 0.0:  # underflow of tiny sizes
        raise ValueError(f"size/size_y give a zero area ({sx} x {sy})")
    return area


def area_spread_normalization(spread: float) -> float:
    """Power-preserving normalisation of Blender's area-light `spread` (dimensionless).

    SPEC §4: 2/(2 + (2a − π) tan a) with a = (π − s)/2. Since 2a − π = −s and
    tan a = cot(s/2), this equals 1/(1 − b·cot b) with b = s/2: exactly the
    factor that keeps the emitted power of the attenuated light equal to the
    Lambertian one. Evaluated in that form (with a series for small b, where
    the subtraction cancels). Exactly 1 at s = π.
    """
    s = _number("spread", spread, positive=True)
    if s > _PI_FLOAT32:
        raise ValueError(f"spread must be in (0, π], got {s}")
    s = min(s, math.pi)
    if s >= math.pi:
        return 1.0
    b = 0.5 * s
    if b < 1e-2:
        # 1 − b cot b = b²/3 + b⁴/45 + 2b⁶/945 + ...
        b2 = b * b
        denom = b2 / 3.0 + b2 * b2 / 45.0 + 2.0 * b2 * b2 * b2 / 945.0
    else:
        denom = 1.0 - b * math.cos(b) / math.sin(b)
    return 1.0 / denom


def area_spread_factor(theta, spread: float):
    """Scale on an area light's radiance at angle θ from its normal (dimensionless).

    SPEC §4: max(0, 1 − tan a · tan θ) · 2/(2 + (2a − π) tan a), a = (π − s)/2.
    tan a = cot(s/2), so the light is cut off at θ = s/2 (the spread's half
    angle). θ is in radians (float or numpy array); θ ≥ π/2 (behind the light)
    gives 0. At s = π the factor is exactly 1 for every θ in front.
    """
    norm = area_spread_normalization(spread)
    s = float(spread)
    try:
        import numpy as np
    except ImportError:  # pragma: no cover - numpy ships with Blender
        np = None
    if np is not None and not isinstance(theta, (int, float)):
        th = np.asarray(theta, dtype=float)
        if np.any(np.isnan(th)):
            raise ValueError("theta must not be NaN")
        front = np.abs(th) < 0.5 * math.pi
        if s >= math.pi:
            return np.where(front, 1.0, 0.0)
        b = 0.5 * s
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.tan(np.where(front, np.abs(th), 0.0)) * (math.cos(b) / math.sin(b))
        return np.where(front, np.maximum(0.0, 1.0 - t) * norm, 0.0)
    th = abs(float(theta))
    if math.isnan(th):
        raise ValueError("theta must not be NaN")
    if th >= 0.5 * math.pi:
        return 0.0
    if s >= math.pi:
        return 1.0
    b = 0.5 * s
    return max(0.0, 1.0 - math.tan(th) * math.cos(b) / math.sin(b)) * norm


def area_light(
    energy: float,
    color: Sequence[float],
    shape: str,
    size: float,
    size_y: Optional[float] = None,
    spread: float = math.pi,
) -> AreaLightUnits:
    """Cycles 3.4 area light: one-sided radiance L = P·c/(4A) toward local −Z.

    energy P in W, color c linear RGB, size/size_y in m, spread in rad.
    The radiance at angle θ from −Z is L · area_spread_factor(θ, spread).
    """
    p = _number("energy", energy)
    c = _color("color", color)
    area = area_light_area(shape, size, size_y)
    norm = area_spread_normalization(spread)
    return AreaLightUnits(_scale(c, p / (4.0 * area)), area, float(spread), norm)


# --------------------------------------------------------------------------
# Point and spot lights


class PointLightUnits(NamedTuple):
    intensity: RGB                 # W/sr, I = P·c/(4π)
    radius: float                  # m; 0 = delta light
    disk_radiance: Optional[RGB]   # W/(m² sr) of the disk facing x (radius > 0), else None
    disk_area: float               # m², π r² (0 for a delta light)


def point_light(energy: float, color: Sequence[float], radius: float = 0.0) -> PointLightUnits:
    """Cycles 3.4 point light: intensity I = P·c/(4π) W/sr (P in W).

    With radius r > 0 Cycles emits from a disk of radius r that always faces the
    shading point, of radiance P·c/(4π·πr²), so far away it matches I/d².
    """
    p = _number("energy", energy)
    c = _color("color", color)
    r = _number("radius", radius)
    intensity = _scale(c, p / (4.0 * math.pi))
    if r == 0.0:
        return PointLightUnits(intensity, 0.0, None, 0.0)
    disk_area = math.pi * r * r
    if not disk_area > 0.0:
        raise ValueError(f"radius {r} gives a zero disk area")
    return PointLightUnits(intensity, r, _scale(intensity, 1.0 / disk_area), disk_area)


class SpotLightUnits(NamedTuple):
    intensity: RGB                 # W/sr on the axis, P·c/(4π), not renormalised by the cone
    radius: float
    disk_radiance: Optional[RGB]
    disk_area: float
    half_angle: float              # rad, spot_size / 2
    cos_half_angle: float          # cos(spot_size / 2): no light at or below this cosine
    smooth_width: float            # (1 − cos_half_angle)·spot_blend, in cosine units


def spot_cone(spot_size: float, spot_blend: float) -> Tuple[float, float, float]:
    """Cone of a Blender spot light as Cycles 3.4 sets it up.

    spot_size is the full cone angle (rad, Blender allows up to π);
    spot_blend in [0, 1]. Returns (half_angle, cos_half_angle, smooth_width)
    with half_angle = spot_size/2 and smooth_width = (1 − cos_half_angle)·spot_blend:
    the blend acts in cosine space, over the cosines
    [cos_half_angle, cos_half_angle + smooth_width] inside the cone edge.
    """
    size = _number("spot_size", spot_size, positive=True)
    if size > _PI_FLOAT32:
        raise ValueError(f"spot_size must be in (0, π], got {size}")
    size = min(size, math.pi)
    blend = _number("spot_blend", spot_blend)
    if blend > 1.0:
        raise ValueError(f"spot_blend must be in [0, 1], got {blend}")
    half = 0.5 * min(size, math.pi)
    cos_half = math.cos(half)
    return half, cos_half, (1.0 - cos_half) * blend


def spot_attenuation(cos_axis, spot_size: float, spot_blend: float, *, cycles_cosine: bool = True):
    """Scale on a spot light's intensity toward a direction (dimensionless).

    cos_axis: cosine of the angle between the spot axis (local −Z) and the
    direction from the light to the shading point (float or numpy array).

    Reading of SPEC §4 ("as point inside the cone, smoothstep falloff by
    spot_blend"), following the Cycles 3.x kernel (spot_light_attenuation):
        a = cos_axis                          (if cycles_cosine, else 1)
        0                                     if cos_axis <= cos_half_angle
        a · smoothstep(t / smooth_width)      if t = cos_axis − cos_half_angle < smooth_width
        a                                     otherwise
    with smoothstep(x) = x²(3 − 2x). Note the Cycles kernel starts from
    attenuation = cos_axis, i.e. the intensity inside the cone also falls off
    with the cosine to the axis; SPEC's wording ("as point inside the cone")
    omits it. A bake on this Blender 3.4.1 confirms the cosine (spot at 1 m,
    120° cone, point 1.03 m off axis: 5.947 baked, 5.943 with it, 8.54 without).
    cycles_cosine=False gives SPEC's literal reading.
    """
    _, cos_half, smooth = spot_cone(spot_size, spot_blend)

    def one(c: float) -> float:
        if math.isnan(c):
            raise ValueError("cos_axis must not be NaN")
        if c <= cos_half:
            return 0.0
        a = c if cycles_cosine else 1.0
        t = c - cos_half
        if smooth != 0.0 and t < smooth:
            x = t / smooth
            a *= x * x * (3.0 - 2.0 * x)
        return a

    if isinstance(cos_axis, (int, float)):
        return one(float(cos_axis))
    import numpy as np

    c = np.asarray(cos_axis, dtype=float)
    if np.any(np.isnan(c)):
        raise ValueError("cos_axis must not be NaN")
    a = c.copy() if cycles_cosine else np.ones_like(c)
    if smooth != 0.0:
        x = np.clip((c - cos_half) / smooth, 0.0, 1.0)
        a = a * (x * x * (3.0 - 2.0 * x))
    return np.where(c > cos_half, a, 0.0)


def spot_light(
    energy: float,
    color: Sequence[float],
    spot_size: float,
    spot_blend: float,
    radius: float = 0.0,
) -> SpotLightUnits:
    """Cycles 3.4 spot light: a point light (P·c/(4π) W/sr, optional facing disk of
    radius r) times spot_attenuation(); the power is not renormalised by the cone.
    """
    pt = point_light(energy, color, radius)
    half, cos_half, smooth = spot_cone(spot_size, spot_blend)
    return SpotLightUnits(pt.intensity, pt.radius, pt.disk_radiance, pt.disk_area,
                          half, cos_half, smooth)


# --------------------------------------------------------------------------
# Sun


class SunLightUnits(NamedTuple):
    irradiance: RGB              # W/m² on a surface facing the sun, S·c (angle 0)
    half_angle: float            # rad, angle / 2 (Blender's angle is the full diameter)
    solid_angle: float           # sr, 2π(1 − cos half_angle); 0 for a delta sun
    radiance_on_axis: Optional[RGB]  # W/(m² sr) toward the sun's centre (angle > 0), else None
    normal_irradiance: RGB       # W/m² a facing surface really receives: S·c·2cosα/(1+cosα)


def sun_light(strength: float, color: Sequence[float], angle: float = 0.0) -> SunLightUnits:
    """Cycles 3.4 sun: irradiance S·c W/m² on a surface facing it (S = strength).

    angle is Blender's angular diameter (rad); the cone half-angle is α = angle/2.
    For angle > 0 SPEC says "spread uniformly over a cone"; Cycles 3.4 does it
    with a disk of radius tan α at unit distance whose directions are drawn
    uniformly on the disk, and radiance equal to that pdf:
        L(θ') = S·c / (π tan²α · cos³θ')  for θ' < α (θ' from the sun's axis)
    (sun_radiance()). A facing surface then gets S·c·2cosα/(1 + cosα), not S·c:
    0.99999·S at Blender's default 0.526°, 0.928·S at 60° (measured on this
    Blender: 0.928 for S = π, angle 60°).
    """
    s = _number("strength", strength)
    c = _color("color", color)
    a = _number("angle", angle)
    if a >= math.pi:
        raise ValueError(f"angle must be in [0, π), got {a}")
    e = _scale(c, s)
    if a == 0.0:
        return SunLightUnits(e, 0.0, 0.0, None, e)
    half = 0.5 * a
    tan_half = math.tan(half)
    on_axis = _scale(e, 1.0 / (math.pi * tan_half * tan_half))
    solid_angle = 2.0 * math.pi * (1.0 - math.cos(half))
    cos_half = math.cos(half)
    return SunLightUnits(e, half, solid_angle, on_axis, _scale(e, 2.0 * cos_half / (1.0 + cos_half)))


def sun_radiance(cos_axis, strength: float, color: Sequence[float], angle: float):
    """Radiance W/(m² sr) of a Cycles 3.4 sun of angle > 0 toward a direction at
    cosine cos_axis from the sun's centre: S·c/(π tan²α cos³θ') inside the cone
    (cos_axis > cos α), 0 outside. Returns an RGB tuple (cos_axis a float)."""
    u = sun_light(strength, color, angle)
    if u.radiance_on_axis is None:
        raise ValueError("angle must be positive for a sun with a radiance")
    c = float(cos_axis)
    if math.isnan(c):
        raise ValueError("cos_axis must not be NaN")
    if c <= math.cos(u.half_angle):
        return (0.0, 0.0, 0.0)
    return _scale(u.radiance_on_axis, 1.0 / (c * c * c))


# --------------------------------------------------------------------------
# Emission and world


def mesh_emission(strength: float, color: Sequence[float]) -> RGB:
    """Radiance W/(m² sr) of a mesh with an Emission shader (or Principled BSDF
    emission): L = S·c. Cycles emits it from both sides of the surface."""
    s = _number("strength", strength)
    return _scale(_color("color", color), s)


def world_background(color: Sequence[float], strength: float) -> RGB:
    """Constant radiance W/(m² sr) of a uniform world background: L = S·c from
    every direction (a facing surface receives π·L, so E/π = L)."""
    s = _number("strength", strength)
    return _scale(_color("color", color), s)
