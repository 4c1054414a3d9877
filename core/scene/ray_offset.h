// Moving a ray origin off the surface it starts on, so the ray does not hit
// that surface again, by no more than the floating-point error of the point.
// Following pbrt-v4's error-bounded spawn rays (Pharr, Jakob, Humphreys,
// "Physically Based Rendering" 4th ed., §6.8): bound the absolute error of the
// point per coordinate, move along the geometric normal by that bound
// projected onto it, and round each coordinate away from the surface.
//
// Embree stores geometry and rays in single precision, so the error that
// matters is float error: the surface Embree sees is the float-rounded one,
// the origin is rounded to float, and Embree's ray–triangle test works in
// float. The offset therefore scales with float ulps of the point — large far
// from the world origin, tiny in a scene measured in nanometres — with no
// fixed minimum that would step over small occluders.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "math/vec3.h"

namespace omis {

namespace ray_offset_detail {
constexpr double kFloatEpsilon = std::numeric_limits<float>::epsilon() / 2;  // unit roundoff
// Error bound for a float computation with n rounding steps, γ_n of pbrt
// (Higham): n·u / (1 − n·u). The vertices, the origin and Embree's test each
// round a few times; 16 steps cover them with a margin (pbrt needs γ_7 for
// barycentric interpolation alone).
constexpr double gamma(int n) { return n * kFloatEpsilon / (1 - n * kFloatEpsilon); }
constexpr double kPointGamma = gamma(16);
// Embree may flush denormal floats to zero (DAZ/FTZ), so an origin must stand
// off by a normal float at least: the bound never goes under 16 × FLT_MIN.
constexpr double kAbsoluteFloor = 16.0 * std::numeric_limits<float>::min();

// Rounds x one float-sized step further in the direction `sign` (like pbrt's
// NextFloatUp/Down, in double with float spacing), so the conversion to float
// cannot pull the origin back onto the surface.
// The step is 2^(e − 24) for x = m·2^e, m ∈ [0.5, 1), at least FLT_MIN: read
// from x's exponent bits where x is a normal double (frexp and ldexp were
// ~1.5 % of a light sample), else by frexp (0, subnormal, inf, NaN).
inline double step_away(double x, double sign) {
    if (sign == 0.0) return x;
    constexpr int kFloatDigits = std::numeric_limits<float>::digits;
    constexpr int kFloatMinExponent = std::numeric_limits<float>::min_exponent - 1;  // FLT_MIN = 2^−126
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    const int biased = int(bits >> 52 & 0x7ff);
    double ulp;
    if (biased != 0 && biased != 0x7ff) {
        const int step_exponent = biased - 1022 - kFloatDigits;  // frexp's e − 24
        const int exponent = std::max(step_exponent, kFloatMinExponent);
        const std::uint64_t step_bits = std::uint64_t(exponent + 1023) << 52;
        std::memcpy(&ulp, &step_bits, sizeof ulp);
    } else {
        int e = 0;
        std::frexp(x, &e);
        ulp = std::max(std::ldexp(1.0, e - kFloatDigits), double(std::numeric_limits<float>::min()));
    }
    return x + std::copysign(ulp, sign);
}
}  // namespace ray_offset_detail

// Embree refuses (asserts on) rays whose origin or direction exceeds its
// FLT_LARGE = 1.844e18 in any coordinate: points, vertices and light
// positions stay within this.
constexpr double kLargestTraceableCoordinate = 1e18;

inline bool traceable(const Vec3& p) {
    return std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) <= kLargestTraceableCoordinate;
}

// Per-coordinate absolute error bound of a point interpolated from a
// triangle's vertices with barycentrics b (pbrt: γ·Σ|b_i p_i|).
inline Vec3 interpolation_error(const Vec3& b, const Vec3& p0, const Vec3& p1, const Vec3& p2) {
    auto bound = [&](double a0, double a1, double a2) {
        return ray_offset_detail::kPointGamma *
                   (std::abs(b.x * a0) + std::abs(b.y * a1) + std::abs(b.z * a2)) +
               ray_offset_detail::kAbsoluteFloor;
    };
    return {bound(p0.x, p1.x, p2.x), bound(p0.y, p1.y, p2.y), bound(p0.z, p1.z, p2.z)};
}

// Error bound of a point known only by its coordinates (a caller's shading
// point): float rounding at the scale of its largest coordinate, because the
// triangle it lies on passes through p with vertices rounded at that scale.
inline Vec3 point_error(const Vec3& p) {
    const double scale = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    const double e = ray_offset_detail::kPointGamma * scale + ray_offset_detail::kAbsoluteFloor;
    return {e, e, e};
}

// Origin for a ray leaving point p (error bound p_error per coordinate, on a
// surface with geometric normal ng of any length and orientation) in
// `direction`: p pushed along the normal, to the side the ray leaves towards,
// by the error projected onto the normal, then rounded away.
inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& ng, const Vec3& direction,
                              const Vec3& p_error) {
    // Scale first so a huge or tiny normal does not overflow or underflow.
    const double largest = std::max({std::abs(ng.x), std::abs(ng.y), std::abs(ng.z)});
    if (!(largest > 0.0) || !std::isfinite(largest)) return p;
    Vec3 n = ng / largest;
    n = n / length(n);
    if (dot(n, direction) < 0.0) n = -n;
    const double d = std::abs(n.x) * p_error.x + std::abs(n.y) * p_error.y +
                     std::abs(n.z) * p_error.z;
    const Vec3 o = p + d * n;
    using ray_offset_detail::step_away;
    return {step_away(o.x, n.x), step_away(o.y, n.y), step_away(o.z, n.z)};
}

inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& ng, const Vec3& direction) {
    return offset_ray_origin(p, ng, direction, point_error(p));
}

}  // namespace omis
