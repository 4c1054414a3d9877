// The lights along a direction and their shape densities (lights_along.h).
#include "render/lights_along.h"

#include "render/point_lighting_impl.h"

namespace omis {

const std::vector<std::uint32_t>& LightsAlong::of(const Vec3& x, const Vec3& w) {
    Along& a = along_;
    if (listed(x, w)) return a.lights;
    start_list(x, w);
    a.lights.clear();
    context_.scene.emitter_shapes().lights_along(x, w, a.lights);
    const auto& unshaped = context_.scene.unshaped_lights();
    a.lights.insert(a.lights.end(), unshaped.begin(), unshaped.end());
    // The light just sampled toward w lies along it, even where single
    // precision might miss its (enlarged) shape.
    const std::uint32_t drawn = shapes_.last_light_toward(w);
    if (drawn != ~0u) add_if_missing(a.lights, drawn);
    return a.lights;
}

const std::vector<std::uint32_t>& LightsAlong::adopt(const Vec3& x, const Vec3& w,
                                                     std::vector<std::uint32_t>& lights) {
    start_list(x, w);
    along_.lights.swap(lights);
    return along_.lights;
}

const std::vector<double>& LightsAlong::shape_pdfs(const std::vector<std::uint32_t>& along,
                                                   ShapeSampler sampler, const Vec3& x,
                                                   const Vec3& n, const Vec3& w) {
    ShapePdfs& c = shape_pdfs_;
    if (c.along == serial_ && c.sampler == sampler && c.n.x == n.x && c.n.y == n.y &&
        c.n.z == n.z)
        return c.pdf;
    c.along = serial_;
    c.sampler = sampler;
    c.n = n;
    c.pdf.clear();
    const TriangleTest* tests = tests_of(along);
    for (std::size_t i = 0; i < along.size(); ++i)
        c.pdf.push_back(shapes_.pdf(along[i], sampler, x, n, w, tests ? &tests[i] : nullptr));
    counters_.pdf_evaluations += along.size();
    return c.pdf;
}

}  // namespace omis
