// Light evaluation: emitted radiance along a direction, delta lights' illumination,
// shape draws and their densities, reach tests and unoccluded irradiance
// (light factories and their validation: light_factories.cpp).
#include "lights/light.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "lights/environment_map.h"  // image-based world
#include "lights/spread.h"
#include "sampling/irradiance.h"
#include "scene/ray_offset.h"
#include "sampling/warp.h"

namespace omis {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

// An ellipse light as its samplers see it from x: whole, or only a clipped part
// (α, β) of it, or nothing when the spread lets no point reach x.
struct EllipseReach {
    bool whole = true;
    std::optional<ClippedDisk> part;
    bool none() const { return !whole && !part; }
    // A box [a0, a1] × [b0, b1] in (α, β) around what reaches x: the part's,
    // else the whole ellipse's.
    struct Box {
        double a0 = -1, a1 = 1, b0 = -1, b1 = 1;
    };
    Box box() const {
        Box b;
        if (part) {
            const Point2 lo = part->box_min(), hi = part->box_max();
            b = {lo.x, hi.x, lo.y, hi.y};
        }
        return b;
    }
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
            const EllipseReach::Box box = reach.box();
            auto at = [&](double a, double b) { return e.center + e.axis_a * a + e.axis_b * b; };
            return above({at(box.a0, box.b0), at(box.a0, box.b1), at(box.a1, box.b0),
                          at(box.a1, box.b1)});
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
                const EllipseReach::Box box = ellipse_reach(l, x).box();
                return spread_weighted_irradiance(
                    l, x, n, [&](double a, double b) { return e.center + e.axis_a * a + e.axis_b * b; },
                    [](double a, double b) { return a * a + b * b <= 1; }, box.a0, box.a1, box.b0,
                    box.b1, 3);
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
