// The density of every active technique along a direction (technique_pdf):
// a selector's pmf or a table's probability times each light's shape density
// (shape_draws.h), over the lights along the direction (lights_along.h).
#include "render/point_lighting_impl.h"

namespace omis {

double PointLighting::Impl::technique_pdf(int k, const Vec3& x, const Vec3& n, const Vec3& w) {
    const Technique& t = p_.settings.techniques[k];
    if (t.bsdf) return std::max(0.0, dot(n, w)) * kInvPi;
    if (const LightSelector* s = technique_selectors_[k]) {
        // Only lights along w have a density there. Their pmf records are
        // read while their shapes' densities are computed.
        const std::vector<std::uint32_t>& along = lights_along_.of(x, w);
        for (std::uint32_t l : along) s->prefetch(l);
        double pdf = 0;
        const std::vector<double>& shape = lights_along_.shape_pdfs(along, t.sampler, x, n, w);
        LightSelector::Memo* memo;
        const LightSelector::Receiver at = receiver_at(x, n, memo);
        for (std::size_t i = 0; i < along.size(); ++i) {
            // The shape's density first: it is 0 for most extra candidates,
            // and then the tree need not be walked.
            if (!(shape[i] > 0)) continue;
            const SampleSelection& d = sample_selection_;
            pdf += (s == d.selector && along[i] == d.light ? d.pmf : s->pmf(at, along[i], memo)) *
                   shape[i];
        }
        return pdf;
    }
    const LightTable& c = tables_[k];
    double pdf = 0;
    if (p_.settings.fast_paths && (lights_along_.listed(x, w) || c.lights.size() > kFewTableLights)) {
        // As the selectors: only lights along w have a density there (the
        // sphere's near and far triangle, of 16), and a loop over the table
        // tested every light's shape (~29 % of a sample at 16 emitters).
        // The terms summed in the table's order, the others being 0: the
        // loop's sum, bit for bit.
        along_slots_.clear();
        const std::vector<std::uint32_t>& along = lights_along_.of(x, w);
        for (std::size_t j = 0; j < along.size(); ++j) {
            // A table lists its lights in p_.integrated's (ascending) order.
            const auto it = std::lower_bound(c.lights.begin(), c.lights.end(), along[j]);
            if (it != c.lights.end() && *it == along[j])
                along_slots_.push_back({std::size_t(it - c.lights.begin()), j});
        }
        std::sort(along_slots_.begin(), along_slots_.end());
        const TriangleTest* tests = lights_along_.tests_of(along);
        for (const auto& [i, j] : along_slots_)
            pdf += c.probability[i] *
                   shapes_.pdf(c.lights[i], t.sampler, x, n, w, tests ? &tests[j] : nullptr);
        counters.pdf_evaluations += along_slots_.size();
        return pdf;
    }
    for (std::size_t i = 0; i < c.lights.size(); ++i)
        pdf += c.probability[i] * shapes_.pdf(c.lights[i], t.sampler, x, n, w);
    counters.pdf_evaluations += c.lights.size();
    return pdf;
}

}  // namespace omis
