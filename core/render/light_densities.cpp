// Light densities at a shading point: light shape draws and their densities
// (with the per-point solid-angle shapes), the lights along a direction, and
// technique_pdf — the density of every active technique along a direction.
#include "render/point_lighting_impl.h"

namespace omis {

const PointLighting::Impl::SolidAngleCache* PointLighting::Impl::solid_angle(std::uint32_t l,
                                                                             const Vec3& x,
                                                                             const Vec3& n) {
    const Light& light = p_.scene.lights()[l];
    if (light.type != LightType::Rect && light.type != LightType::Triangle &&
        !ellipse_wholly_reaches(light, x))
        return nullptr;  // a spread ellipse's part is drawn by area
    if (p_.scene.lights().size() > kMaxCachedLights) return nullptr;
    if (solid_angle_cache_.size() != p_.scene.lights().size())
        solid_angle_cache_.resize(p_.scene.lights().size());
    SolidAngleCache& c = solid_angle_cache_[l];
    if (c.point != point_serial_ || c.n.x != n.x || c.n.y != n.y || c.n.z != n.z) {
        c.point = point_serial_;
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

std::optional<LightSample> PointLighting::Impl::sample(std::uint32_t l, ShapeSampler sampler,
                                                       const Vec3& x, const Vec3& n, double u1,
                                                       double u2) {
    const Light& light = p_.scene.lights()[l];
    const ShapeSampler asked = sampler;
    if (sampler == ShapeSampler::SolidAngle && tiny(l, light, x))
        sampler = ShapeSampler::Area;
    const SolidAngleCache* c =
        sampler == ShapeSampler::SolidAngle ? solid_angle(l, x, n) : nullptr;
    std::optional<LightSample> s;
    if (!c) s = sample_light(light, sampler, x, n, u1, u2);
    else s = sample_cached(*c, u1, u2);
    if (s) drawn_ = {l, s->dir, asked, s->pdf, point_serial_};
    return s;
}

std::optional<LightSample> PointLighting::Impl::sample_cached(const SolidAngleCache& cache,
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

double PointLighting::Impl::pdf(std::uint32_t l, ShapeSampler sampler, const Vec3& x,
                                const Vec3& n, const Vec3& w, const TriangleTest* known) {
    // The sample's own density, before the light's record is read again
    // for the tiny-light test (the draw made the same choice).
    double drawn;
    if (drawn_density(l, sampler, w, drawn)) return drawn;
    const Light& light = p_.scene.lights()[l];
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

const std::vector<std::uint32_t>& PointLighting::Impl::lights_along(const Vec3& x,
                                                                    const Vec3& w) {
    Along& a = along_;
    if (along_is(x, w)) return a.lights;
    a.x = x;
    a.w = w;
    a.valid = true;
    ++along_serial_;
    a.lights.clear();
    p_.scene.emitter_shapes().lights_along(x, w, a.lights);
    const auto& unshaped = p_.scene.unshaped_lights();
    a.lights.insert(a.lights.end(), unshaped.begin(), unshaped.end());
    // The light just sampled toward w lies along it, even where single
    // precision might miss its (enlarged) shape.
    if (drawn_.light != ~0u && drawn_.w.x == w.x && drawn_.w.y == w.y && drawn_.w.z == w.z &&
        std::find(a.lights.begin(), a.lights.end(), drawn_.light) == a.lights.end())
        a.lights.push_back(drawn_.light);
    return a.lights;
}

const std::vector<double>& PointLighting::Impl::shape_pdfs_along(
    const std::vector<std::uint32_t>& along, ShapeSampler sampler, const Vec3& x, const Vec3& n,
    const Vec3& w) {
    ShapePdfs& c = shape_pdfs_;
    if (c.along == along_serial_ && c.sampler == sampler && c.n.x == n.x && c.n.y == n.y &&
        c.n.z == n.z)
        return c.pdf;
    c.along = along_serial_;
    c.sampler = sampler;
    c.n = n;
    c.pdf.clear();
    const bool tested = &along == &along_.lights && along_.tested == along_serial_;
    for (std::size_t i = 0; i < along.size(); ++i)
        c.pdf.push_back(this->pdf(along[i], sampler, x, n, w, tested ? &along_.tests[i] : nullptr));
    counters.pdf_evaluations += along.size();
    return c.pdf;
}

double PointLighting::Impl::technique_pdf(int k, const Vec3& x, const Vec3& n, const Vec3& w) {
    const Technique& t = p_.settings.techniques[k];
    if (t.bsdf) return std::max(0.0, dot(n, w)) * kInvPi;
    if (const LightSelector* s = technique_selectors_[k]) {
        // Only lights along w have a density there. Their pmf records are
        // read while their shapes' densities are computed.
        const std::vector<std::uint32_t>& along = lights_along(x, w);
        for (std::uint32_t l : along) s->prefetch(l);
        double pdf = 0;
        const std::vector<double>& shape = shape_pdfs_along(along, t.sampler, x, n, w);
        LightSelector::Memo* memo;
        const LightSelector::Receiver at = receiver_at(x, n, memo);
        for (std::size_t i = 0; i < along.size(); ++i) {
            // The shape's density first: it is 0 for most extra candidates,
            // and then the tree need not be walked.
            if (!(shape[i] > 0)) continue;
            const DrawnSelection& d = drawn_selection_;
            pdf += (s == d.selector && along[i] == d.light ? d.pmf : s->pmf(at, along[i], memo)) *
                   shape[i];
        }
        return pdf;
    }
    const LightTable& c = tables_[k];
    double pdf = 0;
    if (p_.settings.fast_paths && (along_is(x, w) || c.lights.size() > kFewTableLights)) {
        // As the selectors: only lights along w have a density there (the
        // sphere's near and far triangle, of 16), and a loop over the table
        // tested every light's shape (~29 % of a sample at 16 emitters).
        // The terms summed in the table's order, the others being 0: the
        // loop's sum, bit for bit.
        along_slots_.clear();
        const std::vector<std::uint32_t>& along = lights_along(x, w);
        for (std::size_t j = 0; j < along.size(); ++j) {
            // A table lists its lights in p_.integrated's (ascending) order.
            const auto it = std::lower_bound(c.lights.begin(), c.lights.end(), along[j]);
            if (it != c.lights.end() && *it == along[j])
                along_slots_.push_back({std::size_t(it - c.lights.begin()), j});
        }
        std::sort(along_slots_.begin(), along_slots_.end());
        const bool tested = along_.tested == along_serial_;
        for (const auto& [i, j] : along_slots_)
            pdf += c.probability[i] *
                   this->pdf(c.lights[i], t.sampler, x, n, w, tested ? &along_.tests[j] : nullptr);
        counters.pdf_evaluations += along_slots_.size();
        return pdf;
    }
    for (std::size_t i = 0; i < c.lights.size(); ++i)
        pdf += c.probability[i] * this->pdf(c.lights[i], t.sampler, x, n, w);
    counters.pdf_evaluations += c.lights.size();
    return pdf;
}

}  // namespace omis
