// Moving a ray origin off the surface it starts on, so the ray does not hit
// that surface again. Embree intersects in single precision, so the offset is
// measured in float ulps of the point's own coordinates (Wächter & Binder,
// "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems
// 2019; pbrt-v4 OffsetRayOrigin follows the same idea with error bounds).
#pragma once

#include <cmath>
#include <limits>

#include "math/vec3.h"

namespace omis {

namespace ray_offset_detail {
// Below this magnitude a coordinate is near the origin, where float ulps become
// tiny and a fixed offset is used instead.
constexpr double kOriginRegion = 1.0 / 32.0;
constexpr double kFixedOffset = 1.0 / 65536.0;
// How many float ulps of the coordinate to move; covers the rounding error of
// Embree's float hit point and of barycentric interpolation with a wide margin.
constexpr double kUlps = 256.0;

// Spacing of floats around |x| (x not tiny): 2^(exponent(x) - 23).
inline double float_ulp(double x) {
    int e = 0;
    std::frexp(x, &e);  // |x| = m * 2^e, m in [0.5, 1)
    return std::ldexp(1.0, e - std::numeric_limits<float>::digits);
}

inline double offset_component(double p, double n) {
    if (std::abs(p) < kOriginRegion) return p + kFixedOffset * n;
    return p + kUlps * float_ulp(p) * n;
}
}  // namespace ray_offset_detail

// Origin for a ray leaving point p (on a surface with geometric normal ng, any
// length and orientation) in `direction`: p pushed to the side of the surface
// the ray leaves towards. Each coordinate moves by an amount proportional to its
// own magnitude, so the result stays off the surface far from the world origin.
inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& ng, const Vec3& direction) {
    const double len = length(ng);
    if (!(len > 0.0)) return p;
    Vec3 n = ng / len;
    if (dot(n, direction) < 0.0) n = -n;
    using ray_offset_detail::offset_component;
    return {offset_component(p.x, n.x), offset_component(p.y, n.y),
            offset_component(p.z, n.z)};
}

}  // namespace omis
