// Light factories: every light made from its parameters, validated first
// (std::invalid_argument naming the problem). Evaluation: light.cpp.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "lights/light.h"
#include "lights/spread.h"
#include "scene/ray_offset.h"

namespace omis {
namespace {

[[noreturn]] void invalid(const std::string& what, const std::string& problem) {
    throw std::invalid_argument(what + ": " + problem);
}

void require_finite(const Vec3& v, const char* what) {
    if (!isfinite(v)) invalid(what, "is not finite");
}

// Positions and spans within Embree's range (distances then never overflow).
void require_traceable(const Vec3& v, const char* what) {
    require_finite(v, what);
    if (!traceable(v)) invalid(what, "lies beyond ±1e18 m, outside the range rays can reach");
}

// Emission at most this large: sample values are squared for the variance
// and the optimal-MIS moments (the estimator refuses values beyond 1e140).
constexpr double kLargestEmission = 1e100;

std::string number(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// A light's size (m², or sr for the sun): its square and its reciprocal
// square must stay finite, as samplers and pdfs use both.
constexpr double kLargestSize = 1e150, kSmallestSize = 1e-150;

// `what` and `given` make the message, built only on failure (a mesh of
// 100k emitting triangles spent a third of its commit formatting them).
template <class What, class Given>
void require_size(double size, What what, Given given, const char* measure) {
    if (!(size <= kLargestSize))
        invalid(what(), given() + " is too large to represent (" + measure + " overflows)");
    if (!(size >= kSmallestSize))
        invalid(what(), given() + " is too small to represent (" + measure + " underflows)");
}

// Unit vector along v, scaled first so huge or tiny vectors do not overflow
// or underflow when squared.
Vec3 unit_direction(const Vec3& v, const char* what) {
    require_finite(v, what);
    const double largest = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    if (!(largest > 0)) invalid(what, "has zero length");
    return normalize(v / largest);
}

// Euclidean length without overflow or underflow of the squares.
double safe_length(const Vec3& v) { return std::hypot(v.x, v.y, v.z); }


void require_emission(const Vec3& e, const char* what) {
    require_finite(e, what);
    if (e.x < 0 || e.y < 0 || e.z < 0) invalid(what, "must not be negative");
    if (std::max({e.x, e.y, e.z}) > kLargestEmission)
        invalid(what, number(std::max({e.x, e.y, e.z})) + " exceeds the supported " +
                          number(kLargestEmission));
}

// Relative tolerance for "perpendicular" edges and axes.
void require_perpendicular(const Vec3& a, const Vec3& b, const char* what) {
    if (std::abs(dot(a, b)) > 1e-6 * length(a) * length(b))
        invalid(what, "edges/axes must be perpendicular");
}

}  // namespace

namespace {

// The checks and fields rect and ellipse lights share: an origin point and
// two perpendicular spanning vectors (edges or semi-axes).
Light planar_light(LightType type, const char* what, const Vec3& origin, const char* origin_name,
                   const Vec3& a, const char* a_name, const Vec3& b, const char* b_name,
                   const Vec3& radiance, bool two_sided, double spread) {
    require_traceable(origin, origin_name);
    require_traceable(a, a_name);
    require_traceable(b, b_name);
    require_emission(radiance, "radiance");
    // Directions and lengths apart, so huge or tiny spans neither overflow
    // nor underflow before the area is judged.
    const double len_a = safe_length(a), len_b = safe_length(b);
    if (!(len_a > 0 && len_b > 0)) invalid(what, "has zero area");
    const Vec3 unit_a = unit_direction(a, a_name), unit_b = unit_direction(b, b_name);
    if (!(length(cross(unit_a, unit_b)) > 0)) invalid(what, "has zero area");
    require_perpendicular(unit_a, unit_b, what);
    const double area = (type == LightType::Ellipse ? kPi : 1.0) * len_a * len_b;
    require_size(
        area, [&] { return std::string(a_name) + ", " + b_name; },
        [&] { return number(len_a) + " m × " + number(len_b) + " m"; }, "area");
    if (!(spread > 0 && spread <= kPi)) invalid("spread", "must lie in (0, π]");
    Light l;
    l.type = type;
    l.emission = radiance;
    l.two_sided = two_sided;
    l.spread = spread;
    return l;
}

}  // namespace

// Edges that pass the 1e-6 perpendicularity check (float32 world matrices
// leave ~1e-9) are made exactly perpendicular: the spherical-rectangle and
// ellipse samplers assume it, and would otherwise refuse the light.
namespace {
Vec3 orthogonal_part(const Vec3& b, const Vec3& a) { return b - a * (dot(a, b) / dot(a, a)); }
}  // namespace

Light make_rect_light(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                      const Vec3& radiance, bool two_sided, double spread) {
    Light l = planar_light(LightType::Rect, "rect light", corner, "corner", edge_u, "edge_u",
                           edge_v, "edge_v", radiance, two_sided, spread);
    l.rect = RectLight{corner, edge_u, orthogonal_part(edge_v, edge_u)};
    l.spread_constants = spread_constants(spread, l.rect.edge_u, l.rect.edge_v);
    return l;
}

Light make_ellipse_light(const Vec3& center, const Vec3& axis_a, const Vec3& axis_b,
                         const Vec3& radiance, bool two_sided, double spread) {
    Light l = planar_light(LightType::Ellipse, "ellipse light", center, "center", axis_a,
                           "axis_u", axis_b, "axis_v", radiance, two_sided, spread);
    l.ellipse = EllipseLight{center, axis_a, orthogonal_part(axis_b, axis_a)};
    l.spread_constants = spread_constants(spread, l.ellipse.axis_a, l.ellipse.axis_b);
    return l;
}

Light make_triangle_light(const Vec3& p0, const Vec3& p1, const Vec3& p2,
                          const Vec3& radiance, bool two_sided) {
    require_traceable(p0, "triangle");
    require_traceable(p1, "triangle");
    require_traceable(p2, "triangle");
    require_emission(radiance, "radiance");
    // The cross product of edges scaled to at most 1, then the scale back.
    const Vec3 e1 = p1 - p0, e2 = p2 - p0;
    const double scale = std::max({std::abs(e1.x), std::abs(e1.y), std::abs(e1.z),
                                   std::abs(e2.x), std::abs(e2.y), std::abs(e2.z)});
    const double unit_area = scale > 0 ? 0.5 * length(cross(e1 / scale, e2 / scale)) : 0.0;
    if (!(unit_area > 0)) invalid("triangle light", "has zero area");
    const double area = unit_area * scale * scale;
    require_size(
        area, [] { return std::string("triangle"); },
        [&] { return "an area of " + number(area) + " m²"; }, "area");
    Light l;
    l.type = LightType::Triangle;
    l.triangle = TriangleLight{p0, p1, p2};
    l.triangle_area = l.triangle.area();
    l.emission = radiance;
    l.two_sided = two_sided;
    return l;
}

Light make_point_light(const Vec3& position, const Vec3& intensity, double radius) {
    require_traceable(position, "position");
    require_emission(intensity, "intensity");
    if (!(radius >= 0) || !std::isfinite(radius)) invalid("radius", "must be ≥ 0 and finite");
    // A sphere of radius r lights a point at distance d as a point light does, to
    // O((r/d)²): below a micrometre, 1e-6 relative from a millimetre on. Smaller
    // spheres are points, rather than cones too narrow to sample in double
    // precision (they would light nothing).
    constexpr double kSmallestSphereRadius = 1e-6;
    if (radius < kSmallestSphereRadius) radius = 0;
    Light l;
    l.type = LightType::Point;
    l.position = position;
    l.emission = intensity;
    l.radius = radius;
    return l;
}

Light make_spot_light(const Vec3& position, const Vec3& direction, const Vec3& intensity,
                      double radius, double spot_size, double spot_blend) {
    Light l = make_point_light(position, intensity, radius);
    const Vec3 axis = unit_direction(direction, "direction");
    if (!(spot_size > 0 && spot_size <= kPi)) invalid("spot_size", "must lie in (0, π]");
    if (!(spot_blend >= 0 && spot_blend <= 1)) invalid("spot_blend", "must lie in [0, 1]");
    l.type = LightType::Spot;
    l.spot_axis = axis;
    l.spot_cos_half = std::cos(0.5 * spot_size);
    l.spot_smooth = (1 - l.spot_cos_half) * spot_blend;
    return l;
}

Light make_sun_light(const Vec3& direction, const Vec3& irradiance, double angle) {
    const Vec3 to_sun = -unit_direction(direction, "direction");
    require_emission(irradiance, "irradiance");
    if (!(angle >= 0 && angle < kPi)) invalid("angle", "must lie in [0, π)");
    Light l;
    l.type = LightType::Sun;
    l.to_sun = to_sun;
    l.emission = irradiance;
    // A disc whose angular radius has cosine 1 in double precision is a delta
    // sun to that precision (the difference is O(angle²) < 1e-16 relative).
    l.sun_half_angle = std::cos(0.5 * angle) < 1.0 ? 0.5 * angle : 0.0;
    return l;
}

Light make_world_light(const Vec3& radiance) {
    require_emission(radiance, "radiance");
    Light l;
    l.type = LightType::World;
    l.emission = radiance;
    return l;
}

Light make_mesh_light(std::uint32_t mesh, const Vec3& centre, double radius, double area,
                      const Vec3& radiance) {
    require_emission(radiance, "radiance");
    require_finite(centre, "centre");
    if (!(radius > 0) || !std::isfinite(radius) || !(area > 0) || !std::isfinite(area))
        throw std::invalid_argument("mesh light: radius and area must be positive and finite");
    Light l;
    l.type = LightType::Mesh;
    l.two_sided = true;
    l.mesh = mesh;
    l.emission = radiance;
    l.position = centre;
    l.radius = radius;
    l.mesh_area = area;
    return l;
}

}  // namespace omis
