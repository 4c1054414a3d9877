#include "lights/light.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "lights/environment_map.h"  // image-based world
#include "sampling/irradiance.h"
#include "scene/ray_offset.h"
#include "sampling/warp.h"

namespace omis {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

// Blender's spread (SPEC §4): radiance × max(0, 1 − tan a tan θ) × normalisation,
// a = (π − s)/2. The normalisation 2/(2 + (2a − π) tan a) equals 1/(1 − b cot b)
// with b = s/2, evaluated by its series where it would cancel. The two
// constants are the light's (Light::spread_constants, made with it).
struct SpreadProfile {
    double tan_a = 0, one_minus_b_cot_b = 1;
    explicit SpreadProfile(double spread) {
        const double b = 0.5 * spread;
        one_minus_b_cot_b = b < 1e-3 ? b * b / 3 + b * b * b * b / 45 : 1 - b / std::tan(b);
        tan_a = 1.0 / std::tan(b);  // tan((π − s)/2) = cot(s/2)
    }
    explicit SpreadProfile(const Light::SpreadConstants& k)
        : tan_a(k.cot_half), one_minus_b_cot_b(k.one_minus_b_cot_b) {}
    double factor(double cos_theta) const {
        const double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
        const double tan_theta = sin_theta / std::max(cos_theta, 1e-300);
        return std::max(0.0, 1 - tan_a * tan_theta) / one_minus_b_cot_b;
    }
};


// Cycles 3.4 spot falloff for the unit direction from the light to the
// receiver: the cosine to the axis inside the cone, smoothstep over the blend.
double spot_attenuation(const Light& light, const Vec3& light_to_x) {
    const double c = dot(light_to_x, light.spot_axis);
    if (c <= light.spot_cos_half) return 0.0;
    double attenuation = c;
    const double t = c - light.spot_cos_half;
    if (light.spot_smooth > 0 && t < light.spot_smooth) {
        const double s = t / light.spot_smooth;
        attenuation *= s * s * (3 - 2 * s);
    }
    return attenuation;
}

bool has_radius(const Light& l) {
    return (l.type == LightType::Point || l.type == LightType::Spot) && l.radius > 0;
}

SphereLight sphere_of(const Light& l) { return SphereLight{l.position, l.radius}; }
SunLight sun_of(const Light& l) { return SunLight{l.to_sun, l.sun_half_angle}; }

// Emission normal of a planar light (unnormalised).
Vec3 planar_normal(const Light& l) {
    switch (l.type) {
        case LightType::Rect: return cross(l.rect.edge_u, l.rect.edge_v);
        case LightType::Ellipse: return cross(l.ellipse.axis_a, l.ellipse.axis_b);
        default: return cross(l.triangle.p1 - l.triangle.p0, l.triangle.p2 - l.triangle.p0);
    }
}

// normalize(planar_normal(l)); a triangle's from its area, the normal's
// length over 2 (the same division: bit for bit).
Vec3 planar_unit_normal(const Light& l) {
    if (l.type == LightType::Triangle) return planar_normal(l) / (2 * l.triangle_area);
    return normalize(planar_normal(l));
}

// Radiance leaving a planar light toward x along −w, or zero from its back.
Vec3 planar_radiance(const Light& l, const Vec3& w) {
    const Vec3 normal = planar_unit_normal(l);
    double cos_l = -dot(w, normal);
    if (l.two_sided) cos_l = std::abs(cos_l);
    if (cos_l <= 0) return {};
    if (l.spread >= kPi) return l.emission;
    return l.emission * SpreadProfile(l.spread_constants).factor(cos_l);
}

// Blender's spread (SPEC §4) lets an emitting point reach x only when x lies
// within s/2 of the light's normal seen from that point: those points form the
// disk of radius |z|·tan(s/2) about x's foot on the light's plane. Cycles 3.4
// samples only the part of a rectangle inside that disk's bounding square
// (area_light_spread_clamp_area_light in kernel/light/area.h); rects and ellipses
// do so here. The box is in the light's own coordinates along e1 and e2.
struct SpreadBox {
    double a0, a1, b0, b1;
};

SpreadBox spread_box(const Light::SpreadConstants& k, const Vec3& x, const Vec3& origin,
                     const Vec3& e1, const Vec3& e2) {
    const Vec3 d = x - origin;
    const double l1 = dot(e1, e1), l2 = dot(e2, e2);
    const double z = std::abs(dot(d, k.unit_normal));
    const double radius = z * k.tan_half;
    const double fa = dot(d, e1) / l1, fb = dot(d, e2) / l2;
    const double ra = radius / k.length1, rb = radius / k.length2;
    return {fa - ra, fa + ra, fb - rb, fb + rb};
}

// The constants spread_box and the falloff take for a light spanned by e1, e2
// (the same arithmetic as computing them at every call, once).
Light::SpreadConstants spread_constants(double spread, const Vec3& e1, const Vec3& e2) {
    Light::SpreadConstants k;
    const double b = 0.5 * spread;
    const SpreadProfile profile(spread);
    k.tan_half = std::tan(b);
    k.cot_half = profile.tan_a;
    k.one_minus_b_cot_b = profile.one_minus_b_cot_b;
    k.unit_normal = normalize(cross(e1, e2));
    k.length1 = std::sqrt(dot(e1, e1));
    k.length2 = std::sqrt(dot(e2, e2));
    return k;
}

// An ellipse light as its samplers see it from x: whole, or only a clipped part
// (α, β) of it, or nothing when the spread lets no point reach x.
struct EllipseReach {
    bool whole = true;
    std::optional<ClippedDisk> part;
    bool none() const { return !whole && !part; }
};

EllipseReach ellipse_reach(const Light& l, const Vec3& x) {
    EllipseReach r;
    if (l.spread >= kPi) return r;
    const EllipseLight& e = l.ellipse;
    const SpreadBox b = spread_box(l.spread_constants, x, e.center, e.axis_a, e.axis_b);
    if (b.a0 <= -1 && b.a1 >= 1 && b.b0 <= -1 && b.b1 >= 1) return r;
    r.whole = false;
    r.part = ClippedDisk::make(std::max(b.a0, -1.0), std::min(b.a1, 1.0), std::max(b.b0, -1.0),
                               std::min(b.b1, 1.0));
    return r;
}

}  // namespace

std::optional<RectLight> rect_reaching(const Light& l, const Vec3& x) {
    const RectLight& r = l.rect;
    if (l.spread >= kPi) return r;
    const SpreadBox b = spread_box(l.spread_constants, x, r.corner, r.edge_u, r.edge_v);
    const double s0 = std::max(b.a0, 0.0), s1 = std::min(b.a1, 1.0);
    const double v0 = std::max(b.b0, 0.0), v1 = std::min(b.b1, 1.0);
    if (!(s0 < s1 && v0 < v1)) return std::nullopt;
    return RectLight{r.corner + r.edge_u * s0 + r.edge_v * v0, r.edge_u * (s1 - s0),
                     r.edge_v * (v1 - v0)};
}

bool ellipse_wholly_reaches(const Light& l, const Vec3& x) {
    return l.type == LightType::Ellipse && ellipse_reach(l, x).whole;
}

bool ray_crosses_light(const Light& l, const Vec3& x, const Vec3& w) {
    switch (l.type) {
        case LightType::Rect: return l.rect.intersect(x, w).has_value();
        case LightType::Ellipse: return l.ellipse.intersect(x, w).has_value();
        case LightType::Triangle: return l.triangle.intersect(x, w).has_value();
        default: return true;
    }
}

const char* light_type_name(LightType type) {
    switch (type) {
        case LightType::Rect: return "rect";
        case LightType::Ellipse: return "ellipse";
        case LightType::Triangle: return "triangle";
        case LightType::Point: return "point";
        case LightType::Spot: return "spot";
        case LightType::Sun: return "sun";
        case LightType::World: return "world";
        case LightType::Mesh: return "mesh";
    }
    return "unknown";
}

const char* shape_sampler_name(ShapeSampler sampler) {
    switch (sampler) {
        case ShapeSampler::Area: return "area";
        case ShapeSampler::SolidAngle: return "solid-angle";
        case ShapeSampler::Parallel: return "parallel";
        case ShapeSampler::ProjectedSolidAngle: return "projected-solid-angle";
    }
    return "unknown";
}

bool Light::is_delta() const {
    switch (type) {
        case LightType::Point:
        case LightType::Spot: return radius <= 0;
        case LightType::Sun: return sun_half_angle <= 0;
        default: return false;
    }
}

double Light::power(double scene_radius) const {
    const double lum = luminance(emission);
    const double sides = two_sided ? 2.0 : 1.0;
    switch (type) {
        case LightType::Rect: return kPi * rect.area() * lum * sides;
        case LightType::Ellipse: return kPi * ellipse.area() * lum * sides;
        case LightType::Triangle: return kPi * triangle.area() * lum * sides;
        case LightType::Point:
        case LightType::Spot: return 4 * kPi * lum;  // Cycles does not renormalise spots
        case LightType::Sun: return lum * kPi * scene_radius * scene_radius;
        case LightType::World: return kPi * lum * kPi * scene_radius * scene_radius;
        case LightType::Mesh: return kPi * mesh_area * lum * 2;  // its triangles', both sides
    }
    return 0;
}

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

namespace {

// A point this close to a mesh light's bounding sphere (relative to its
// radius), or inside it, sees the mesh over too wide a cone to draw it
// from: it draws the cosine hemisphere instead.
constexpr double kMeshConeMargin = 1e-4;

// A direction ∝ cos θ about n: a world's draw, and a mesh light's from inside
// its sphere.
std::optional<LightSample> sample_cosine_about(const Vec3& n, double u1, double u2) {
    const Vec3 local = sample_cosine_hemisphere(u1, u2);
    const double pdf = pdf_cosine_hemisphere(local);
    if (!(pdf > 0)) return std::nullopt;
    return LightSample{Frame(n).to_world(local), kInf, pdf};
}

}  // namespace

bool mesh_light_draws_cone(const Light& l, const Vec3& x) {
    const Vec3 d = l.position - x;
    return dot(d, d) > l.radius * l.radius * (1 + kMeshConeMargin) * (1 + kMeshConeMargin);
}

bool mesh_light_along(const Light& l, const Vec3& x, const Vec3& w) {
    if (!mesh_light_draws_cone(l, x)) return true;
    const Vec3 d = l.position - x;
    const double along = dot(d, w);
    return along > 0 && dot(d, d) - along * along <= l.radius * l.radius;
}

Emitted triangle_emitted(const Light& l, const Vec3& w, double distance) {
    return Emitted{planar_radiance(l, w), distance};
}

std::optional<Emitted> emitted_radiance(const Light& l, const Vec3& x, const Vec3& w) {
    switch (l.type) {
        case LightType::Rect: {
            const auto hit = l.rect.intersect(x, w);
            if (!hit) return std::nullopt;
            return Emitted{planar_radiance(l, w), hit->t};
        }
        case LightType::Ellipse: {
            const auto hit = l.ellipse.intersect(x, w);
            if (!hit) return std::nullopt;
            return Emitted{planar_radiance(l, w), hit->t};
        }
        case LightType::Triangle: {
            const auto hit = l.triangle.intersect(x, w);
            if (!hit) return std::nullopt;
            return triangle_emitted(l, w, hit->t);
        }
        case LightType::Point:
        case LightType::Spot: {
            if (!has_radius(l)) return std::nullopt;
            const auto hit = sphere_of(l).intersect(x, w);
            if (!hit) return std::nullopt;
            // The facing disk's radiance I/(πr²) (SPEC §4); a spot's cone falloff
            // is taken per point of the disk, along the ray (as Cycles 3.4 does).
            Vec3 radiance = l.emission / (kPi * l.radius * l.radius);
            if (l.type == LightType::Spot) radiance *= spot_attenuation(l, -w);
            return Emitted{radiance, hit->t};
        }
        case LightType::Sun: {
            if (l.sun_half_angle <= 0) return std::nullopt;
            const Cone cone = sun_of(l).cone();
            if (!cone.contains(w)) return std::nullopt;
            // Cycles 3.4: a disk of radius tan α at unit distance, radiance
            // S/(π tan²α cos³θ'), θ' from the sun's centre.
            const double tan_a = std::tan(l.sun_half_angle);
            const double c = std::max(dot(w, l.to_sun), 1e-12);
            return Emitted{l.emission / (kPi * tan_a * tan_a * c * c * c), kInf};
        }
        case LightType::World:  // image-based world: environment_map.h
            return Emitted{l.environment ? l.environment->radiance(w) : l.emission, kInf};
        case LightType::Mesh: return std::nullopt;  // its triangles' hits emit
    }
    return std::nullopt;
}

std::optional<DeltaIllumination> delta_illumination(const Light& l, const Vec3& x,
                                                    const Vec3& n) {
    if (!l.is_delta()) return std::nullopt;
    if (l.type == LightType::Sun) {
        const double c = dot(n, l.to_sun);
        if (c <= 0) return std::nullopt;
        return DeltaIllumination{l.emission * c, l.to_sun, kInf};
    }
    const Vec3 d = l.position - x;
    const double dist = length(d);
    if (!(dist > 0)) return std::nullopt;
    const Vec3 w = d / dist;
    const double c = dot(n, w);
    if (c <= 0) return std::nullopt;
    double scale = c / (dist * dist);
    if (l.type == LightType::Spot) scale *= spot_attenuation(l, -w);
    if (scale <= 0) return std::nullopt;
    return DeltaIllumination{l.emission * scale, w, dist};
}

bool light_reaches(const Light& l, const Vec3& x, const Vec3& n) {
    auto above = [&](std::initializer_list<Vec3> vertices) {
        for (const Vec3& v : vertices)
            if (dot(v - x, n) > 0) return true;
        return false;
    };
    auto in_front = [&](const Vec3& on_plane) {
        return l.two_sided || dot(x - on_plane, planar_normal(l)) > 0;
    };
    switch (l.type) {
        case LightType::Rect: {
            const auto r = rect_reaching(l, x);  // with spread: the part that reaches x
            return r && in_front(r->corner) &&
                   above({r->corner, r->corner + r->edge_u, r->corner + r->edge_v,
                          r->corner + r->edge_u + r->edge_v});
        }
        case LightType::Ellipse: {
            const EllipseLight& e = l.ellipse;
            const EllipseReach reach = ellipse_reach(l, x);
            if (reach.none() || !in_front(e.center)) return false;
            double a0 = -1, a1 = 1, b0 = -1, b1 = 1;  // a box around what reaches x
            if (reach.part) {
                const Point2 lo = reach.part->box_min(), hi = reach.part->box_max();
                a0 = lo.x, a1 = hi.x, b0 = lo.y, b1 = hi.y;
            }
            auto at = [&](double a, double b) { return e.center + e.axis_a * a + e.axis_b * b; };
            return above({at(a0, b0), at(a0, b1), at(a1, b0), at(a1, b1)});
        }
        case LightType::Triangle: {
            const TriangleLight& t = l.triangle;
            return in_front(t.p0) && above({t.p0, t.p1, t.p2});
        }
        case LightType::Point:
        case LightType::Spot: {
            if (!has_radius(l)) return false;
            if (dot(l.position - x, n) <= -l.radius) return false;
            if (l.type == LightType::Point) return true;
            // Some point of the disk must see x inside the cone: widen the cone
            // by the disk's angular radius seen from x.
            const Vec3 d = x - l.position;
            const double dist = length(d);
            const double angle = angle_between(d, l.spot_axis);
            return angle < std::acos(l.spot_cos_half) + std::atan2(l.radius, dist);
        }
        case LightType::Sun:
            return l.sun_half_angle > 0 && dot(l.to_sun, n) > -std::sin(l.sun_half_angle);
        case LightType::World: return true;
        case LightType::Mesh: return dot(l.position - x, n) > -l.radius;
    }
    return false;
}

bool sampler_applies(const Light& l, ShapeSampler sampler, const Vec3& x, const Vec3& n) {
    if (!light_reaches(l, x, n)) return false;
    if (sampler == ShapeSampler::ProjectedSolidAngle) {
        // Polygons need an area above the horizon; other shapes fall back to solid angle.
        if (l.type == LightType::Triangle) return l.triangle.projected(x, n).has_value();
        if (l.type != LightType::Rect) return true;
        const auto r = rect_reaching(l, x);
        return r && r->projected(x, n).has_value();
    }
    if (sampler != ShapeSampler::Parallel) return true;
    switch (l.type) {
        case LightType::Rect: {
            const auto r = rect_reaching(l, x);
            return r && r->parallel(x, n).has_value();
        }
        case LightType::Ellipse: return l.ellipse.parallel(x, n).has_value();
        case LightType::Triangle: return l.triangle.parallel(x, n).has_value();
        case LightType::Point:
        case LightType::Spot: return sphere_of(l).facing_disk(x).parallel(x, n).has_value();
        case LightType::Mesh: return true;  // its cone or hemisphere, whatever the sampler
        default: return false;  // no planar region to project for sun and world
    }
}

std::optional<LightSample> sample_light(const Light& l, ShapeSampler sampler, const Vec3& x,
                                        const Vec3& n, double u1, double u2) {
    if (sampler == ShapeSampler::ProjectedSolidAngle) {
        if (l.type == LightType::Triangle) return l.triangle.sample_projected(x, n, u1, u2);
        if (l.type == LightType::Rect) {
            const auto r = rect_reaching(l, x);
            return r ? r->sample_projected(x, n, u1, u2) : std::nullopt;
        }
        sampler = ShapeSampler::SolidAngle;
    }
    switch (l.type) {
        case LightType::Rect: {
            const auto r = rect_reaching(l, x);
            if (!r) return std::nullopt;
            if (sampler == ShapeSampler::Area) return r->sample_area(x, u1, u2);
            if (sampler == ShapeSampler::SolidAngle) return r->sample_solid_angle(x, n, u1, u2);
            return r->sample_parallel(x, n, u1, u2);
        }
        case LightType::Triangle:
            if (sampler == ShapeSampler::Area)
                return l.triangle.sample_area(x, u1, u2, l.triangle_area);
            if (sampler == ShapeSampler::SolidAngle)
                return l.triangle.sample_solid_angle(x, n, u1, u2);
            return l.triangle.sample_parallel(x, n, u1, u2);
        case LightType::Ellipse: {
            // Parallel projects the whole ellipse; area and solid angle draw only
            // the part a spread lets reach x when that is not all of it.
            if (sampler == ShapeSampler::Parallel) return l.ellipse.sample_parallel(x, n, u1, u2);
            const EllipseReach reach = ellipse_reach(l, x);
            if (reach.part) return l.ellipse.sample_clipped(x, *reach.part, u1, u2);
            if (!reach.whole) return std::nullopt;
            if (sampler == ShapeSampler::Area) return l.ellipse.sample_area(x, u1, u2);
            return l.ellipse.sample_solid_angle(x, u1, u2);
        }
        case LightType::Point:
        case LightType::Spot: {
            if (!has_radius(l)) return std::nullopt;
            const SphereLight s = sphere_of(l);
            if (sampler == ShapeSampler::Area) return s.sample_area(x, u1, u2);
            if (sampler == ShapeSampler::SolidAngle) return s.sample_solid_angle(x, u1, u2);
            return s.sample_parallel(x, n, u1, u2);
        }
        case LightType::Sun:
            if (l.sun_half_angle <= 0) return std::nullopt;
            return sun_of(l).sample_solid_angle(u1, u2);
        case LightType::World:  // image-based world: environment_map.h
            if (l.environment) return l.environment->sample(u1, u2);
            return sample_cosine_about(n, u1, u2);
        case LightType::Mesh: {
            // Every sampler: directions toward the bounding sphere, uniform in
            // solid angle; the first hit along one decides what it sees.
            if (!mesh_light_draws_cone(l, x)) return sample_cosine_about(n, u1, u2);
            const Cone c = Cone::around_sphere(x, l.position, l.radius);
            if (!(c.one_minus_cos > 0)) return std::nullopt;
            return LightSample{c.sample(u1, u2), kInf, 1.0 / c.solid_angle()};
        }
    }
    return std::nullopt;
}

double light_pdf(const Light& l, ShapeSampler sampler, const Vec3& x, const Vec3& n,
                 const Vec3& w) {
    if (sampler == ShapeSampler::ProjectedSolidAngle) {
        if (l.type == LightType::Triangle) return l.triangle.pdf_projected(x, n, w);
        if (l.type == LightType::Rect) {
            const auto r = rect_reaching(l, x);
            return r ? r->pdf_projected(x, n, w) : 0.0;
        }
        sampler = ShapeSampler::SolidAngle;
    }
    switch (l.type) {
        case LightType::Rect: {
            const auto r = rect_reaching(l, x);
            if (!r) return 0;
            if (sampler == ShapeSampler::Area) return r->pdf_area(x, w);
            if (sampler == ShapeSampler::SolidAngle) return r->pdf_solid_angle(x, n, w);
            return r->pdf_parallel(x, n, w);
        }
        case LightType::Triangle:
            if (sampler == ShapeSampler::Area) return l.triangle.pdf_area(x, w, l.triangle_area);
            if (sampler == ShapeSampler::SolidAngle) return l.triangle.pdf_solid_angle(x, n, w);
            return l.triangle.pdf_parallel(x, n, w);
        case LightType::Ellipse: {
            if (sampler == ShapeSampler::Parallel) return l.ellipse.pdf_parallel(x, n, w);
            const EllipseReach reach = ellipse_reach(l, x);
            if (reach.part) return l.ellipse.pdf_clipped(x, *reach.part, w);
            if (!reach.whole) return 0;
            if (sampler == ShapeSampler::Area) return l.ellipse.pdf_area(x, w);
            return l.ellipse.pdf_solid_angle(x, w);
        }
        case LightType::Point:
        case LightType::Spot: {
            if (!has_radius(l)) return 0;
            const SphereLight s = sphere_of(l);
            if (sampler == ShapeSampler::Area) return s.pdf_area(x, w);
            if (sampler == ShapeSampler::SolidAngle) return s.pdf_solid_angle(x, w);
            return s.pdf_parallel(x, n, w);
        }
        case LightType::Sun:
            return l.sun_half_angle > 0 ? sun_of(l).pdf_solid_angle(w) : 0;
        case LightType::World:  // image-based world: environment_map.h
            if (l.environment) return l.environment->pdf(w);
            return std::max(0.0, dot(n, w)) * kInvPi;
        case LightType::Mesh: {
            if (!mesh_light_draws_cone(l, x)) return std::max(0.0, dot(n, w)) * kInvPi;
            const Cone c = Cone::around_sphere(x, l.position, l.radius);
            return c.one_minus_cos > 0 ? c.pdf(w) : 0.0;
        }
    }
    return 0;
}

namespace {

// Unoccluded irradiance luminance of a planar light with spread, over the part
// of it in parameter box [a0, a1] × [b0, b1] of `at` (which maps (α, β) to a
// point of the light): the box is cut into cells² cells, and each cell's
// exact Lambert irradiance (as if of uniform radiance) is weighted by the
// mean spread factor over taps² points of the cell (0 at points outside the
// light's shape, `inside`), each point weighted by the Lambert kernel there:
// both peak at x's foot on the light. Cells the shape's edge crosses take
// more taps. Checked against a fine numeric integral in
// tests/core/test_spread_weight.cpp.
template <class At, class Inside>
double spread_weighted_irradiance(const Light& l, const Vec3& x, const Vec3& n, At at,
                                  Inside inside, double a0, double a1, double b0, double b1,
                                  int cells) {
    constexpr int kTaps = 3, kEdgeTaps = 4;
    const Vec3 normal = planar_unit_normal(l);
    const SpreadProfile spread(l.spread_constants);
    const double da = (a1 - a0) / cells, db = (b1 - b0) / cells;
    // Kernel-weighted mean of the spread factor over a cell; `mixed` tells
    // whether the shape's edge crossed it.
    auto mean_factor = [&](double ca, double cb, int taps, bool& mixed) {
        double gk = 0, k = 0;
        int in = 0;
        for (int ti = 0; ti < taps; ++ti)
            for (int tj = 0; tj < taps; ++tj) {
                const double a = ca + (ti + 0.5) * da / taps, b = cb + (tj + 0.5) * db / taps;
                const bool is_in = inside(a, b);
                in += is_in;
                const Vec3 to_x = x - at(a, b);
                const double d2 = dot(to_x, to_x);
                double cos_l = dot(to_x, normal);
                const double cos_x = -dot(to_x, n);
                if (l.two_sided) cos_l = std::abs(cos_l);
                if (!(d2 > 0) || cos_l <= 0 || cos_x <= 0) continue;
                const double kernel = cos_l * cos_x / (d2 * d2);
                k += kernel;
                if (is_in) gk += kernel * spread.factor(cos_l / std::sqrt(d2));
            }
        mixed = in > 0 && in < taps * taps;
        return k > 0 ? gk / k : 0.0;
    };
    double sum = 0;
    for (int i = 0; i < cells; ++i)
        for (int j = 0; j < cells; ++j) {
            const double ca = a0 + i * da, cb = b0 + j * db;
            const double e = polygon_irradiance(
                x, n, {at(ca, cb), at(ca + da, cb), at(ca + da, cb + db), at(ca, cb + db)});
            if (!(e > 0)) continue;
            bool mixed = false;
            double g = mean_factor(ca, cb, kTaps, mixed);
            if (mixed) g = mean_factor(ca, cb, kEdgeTaps, mixed);
            sum += e * g;
        }
    return luminance(l.emission) * sum;
}

}  // namespace

double unoccluded_irradiance(const Light& l, const Vec3& x, const Vec3& n) {
    if (!light_reaches(l, x, n)) return 0;
    const double lum = luminance(l.emission);
    switch (l.type) {
        case LightType::Rect: {
            // With spread, over the part that reaches x, weighted by the spread
            // factor: 2² cells keep it within 10 % (test_spread_weight.cpp), enough
            // for a selection weight computed per texel and pass.
            const RectLight r = *rect_reaching(l, x);
            if (l.spread < kPi)
                return spread_weighted_irradiance(
                    l, x, n, [&](double a, double b) { return r.corner + r.edge_u * a + r.edge_v * b; },
                    [](double, double) { return true; }, 0.0, 1.0, 0.0, 1.0, 2);
            return lum * polygon_irradiance(x, n, {r.corner, r.corner + r.edge_u,
                                                   r.corner + r.edge_u + r.edge_v,
                                                   r.corner + r.edge_v});
        }
        case LightType::Triangle:
            return lum * polygon_irradiance(x, n, {l.triangle.p0, l.triangle.p1, l.triangle.p2});
        case LightType::Ellipse: {
            const EllipseLight& e = l.ellipse;
            if (l.spread < kPi) {
                // Over the ellipse's part inside the spread's box (ellipse_reach),
                // weighted by the spread factor: 3² cells (the ellipse's edge
                // crosses some) keep it within 10 %.
                double a0 = -1, a1 = 1, b0 = -1, b1 = 1;
                const EllipseReach reach = ellipse_reach(l, x);
                if (reach.part) {
                    const Point2 lo = reach.part->box_min(), hi = reach.part->box_max();
                    a0 = lo.x, a1 = hi.x, b0 = lo.y, b1 = hi.y;
                }
                return spread_weighted_irradiance(
                    l, x, n, [&](double a, double b) { return e.center + e.axis_a * a + e.axis_b * b; },
                    [](double a, double b) { return a * a + b * b <= 1; }, a0, a1, b0, b1, 3);
            }
            // A 32-gon is ample for a selection weight (error ~1e-3).
            return lum * ellipse_irradiance(x, n, e.center, e.axis_a, e.axis_b, 32);
        }
        case LightType::Point:
        case LightType::Spot: {
            const EllipseLight disk = sphere_of(l).facing_disk(x);
            double e = lum / (kPi * l.radius * l.radius) *
                       ellipse_irradiance(x, n, disk.center, disk.axis_a, disk.axis_b, 16);
            if (l.type == LightType::Spot) e *= spot_attenuation(l, normalize(x - l.position));
            return e;
        }
        case LightType::Sun:
            // Straddling the horizon still reaches: keep a positive weight.
            return lum * std::max(dot(n, l.to_sun), 0.5 * std::sin(l.sun_half_angle));
        case LightType::World: return kPi * lum;
        case LightType::Mesh: {
            // The bounding sphere's irradiance as if it emitted all over (a
            // selection weight: the mesh fills most of it, Scene::commit),
            // smoothed across the horizon so that it stays positive wherever
            // part of the sphere is above it.
            if (!mesh_light_draws_cone(l, x)) return kPi * lum;
            const Vec3 d = l.position - x;
            const double dist = length(d);
            const double sin_a = std::min(1.0, l.radius / dist), cos_c = dot(n, d) / dist;
            const double cos_eff = cos_c >= sin_a ? cos_c
                                                  : (cos_c + sin_a) * (cos_c + sin_a) / (4 * sin_a);
            return lum * kPi * sin_a * sin_a * cos_eff;
        }
    }
    return 0;
}

}  // namespace omis
