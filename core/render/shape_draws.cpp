// Light shape draws at a shading position and their densities (shape_draws.h).
#include "render/shape_draws.h"

#include "render/point_lighting_impl.h"

namespace omis {

ShapeDraws::ShapeDraws(const LightingContext& context)
    : context_(context),
      reuse_last_pdf_(context.settings.strategy != Strategy::Maximum &&
                      context.settings.strategy != Strategy::Cutoff) {}

bool ShapeDraws::tiny(std::uint32_t l, const Light& light, const Vec3& x) const {
    if (context_.tiny_shapes.empty()) return tiny_in_solid_angle(tiny_shape_of(light), x);
    return tiny_in_solid_angle(context_.tiny_shapes[l], x);
}

const ShapeDraws::SolidAngleCache* ShapeDraws::solid_angle(std::uint32_t l,
                                                                             const Vec3& x,
                                                                             const Vec3& n) {
    const Light& light = context_.scene.lights()[l];
    if (light.type != LightType::Rect && light.type != LightType::Triangle &&
        !ellipse_wholly_reaches(light, x))
        return nullptr;  // a spread ellipse's part is drawn by area
    if (context_.scene.lights().size() > kMaxCachedLights) return nullptr;
    if (solid_angle_cache_.size() != context_.scene.lights().size())
        solid_angle_cache_.resize(context_.scene.lights().size());
    SolidAngleCache& c = solid_angle_cache_[l];
    if (c.point != position_ || c.n.x != n.x || c.n.y != n.y || c.n.z != n.z) {
        c.point = position_;
        c.n = n;
        // RectLight/TriangleLight::sample_solid_angle(x, n, …)'s shape, prepared.
        c.rect.reset();
        c.triangle.reset();
        c.ellipse.reset();
        if (light.type == LightType::Rect) {
            const auto r = rect_reaching(light, x);  // spread: only the part that reaches x
            const auto s = r ? SphericalRect::make(x, r->corner, r->edge_u, r->edge_v)
                             : std::nullopt;
            if (s) c.rect.emplace(*s, n);
        } else if (light.type == LightType::Ellipse) {
            const EllipseLight& e = light.ellipse;
            c.ellipse = SphericalEllipse::make(x, e.center, e.axis_a, e.axis_b);
        } else if (const auto s = SphericalTriangle::make(x, light.triangle.p0,
                                                          light.triangle.p1, light.triangle.p2)) {
            c.triangle.emplace(*s, n);
        }
    }
    return &c;
}

std::optional<LightSample> ShapeDraws::sample(std::uint32_t l, ShapeSampler sampler,
                                                       const Vec3& x, const Vec3& n, double u1,
                                                       double u2) {
    const Light& light = context_.scene.lights()[l];
    const ShapeSampler asked = sampler;
    if (sampler == ShapeSampler::SolidAngle && tiny(l, light, x))
        sampler = ShapeSampler::Area;
    const SolidAngleCache* c =
        sampler == ShapeSampler::SolidAngle ? solid_angle(l, x, n) : nullptr;
    std::optional<LightSample> s;
    if (!c) s = sample_light(light, sampler, x, n, u1, u2);
    else s = sample_cached(*c, u1, u2);
    if (s) last_ = {l, s->dir, asked, s->pdf, position_};
    return s;
}

std::optional<LightSample> ShapeDraws::sample_cached(const SolidAngleCache& cache,
                                                              double u1, double u2) {
    // RectLight/TriangleLight::sample_solid_angle's draw, from the prepared shape.
    if (cache.rect) return warped_solid_angle_sample(*cache.rect, u1, u2);
    if (cache.triangle) return warped_solid_angle_sample(*cache.triangle, u1, u2);
    if (cache.ellipse) {  // EllipseLight::sample_solid_angle's draw
        const DirSample s = cache.ellipse->sample(u1, u2);
        return LightSample{s.dir, s.dist, cache.ellipse->pdf(s.dir)};
    }
    return std::nullopt;
}

double ShapeDraws::pdf(std::uint32_t l, ShapeSampler sampler, const Vec3& x,
                                const Vec3& n, const Vec3& w, const TriangleTest* known) {
    // The sample's own density, before the light's record is read again
    // for the tiny-light test (the draw made the same choice).
    double last;
    if (last_density(l, sampler, w, last)) return last;
    const Light& light = context_.scene.lights()[l];
    if (sampler == ShapeSampler::SolidAngle && tiny(l, light, x))
        sampler = ShapeSampler::Area;
    // Its triangle's hit test along w, where made: TriangleLight::intersect,
    // as pdf_area and ray_crosses_light make it.
    const bool tested = known && known->known && light.type == LightType::Triangle;
    if (tested && sampler == ShapeSampler::Area)
        return light.triangle.pdf_area_at(known->hit, w, light.triangle_area);
    // A direction that misses the light has density 0 there: no need to
    // prepare its shape at x (the hit test's slack keeps the edge).
    if (sampler == ShapeSampler::SolidAngle && !solid_angle_ready(l) &&
        !(tested ? known->hit.has_value() : ray_crosses_light(light, x, w)))
        return 0.0;
    const SolidAngleCache* c =
        sampler == ShapeSampler::SolidAngle ? solid_angle(l, x, n) : nullptr;
    if (!c) return light_pdf(light, sampler, x, n, w);
    if (c->rect) return c->rect->pdf(w);
    if (c->triangle) return c->triangle->pdf(w);
    if (c->ellipse) return c->ellipse->pdf(w);
    return 0.0;
}

}  // namespace omis
