// What a bake leaves in its result (baker.h): the values' noise, mask and
// sample counts, the margin around UV islands, and the statistics.
#include <algorithm>

#include "bake/baker.h"
#include "bake/uv_raster.h"

namespace omis::bake_detail {


// The running means are the values; the noise, mask and sample counts join them.
void Baker::write_outputs() {
    const std::size_t count = layout_.count;
    result_.noise.assign(count, 0.f);
    result_.mask.assign(count, 0.f);
    result_.samples.assign(count, 0);
    BakeStats& stats = result_.stats;
    double sum_error = 0, sum_passes = 0;
    std::size_t n_covered = 0;
    for (std::size_t i = 0; i < count; ++i) {
        result_.samples[i] = means_.state(i).weight;
        if (!layout_.covered(i)) continue;
        const PointState& s = means_.state(i);
        const double err = relative_error(s, &result_.value[3 * i]);
        result_.noise[i] = float(err);
        result_.mask[i] = 1.f;
        sum_error += err;
        sum_passes += s.passes;
        stats.samples += s.weight;
        stats.shadowed_texels += s.draws_per_count > 1;
        stats.max_relative_error = std::max(stats.max_relative_error, err);
        ++n_covered;
    }
    stats.covered = n_covered;
    stats.buried_texels = buried_;
    stats.mean_relative_error = n_covered ? sum_error / n_covered : 0;
    stats.passes_per_texel = n_covered ? sum_passes / n_covered : 0;
}

// The margin around UV islands: copies of the texels it extends.
// (A tile range leaves it to fill_bake_margin, once the ranges are together.)
void copy_margin(const UvCoverage& coverage, const Mesh& mesh, const BakeSettings& settings,
                 float* value, float* noise) {
    const std::vector<std::int64_t> source =
        settings.margin_type == MarginType::AdjacentFaces
            ? adjacent_margin_sources(coverage, mesh, settings.margin)
            : margin_sources(coverage, settings.margin);
    for (std::size_t i = 0; i < coverage.triangle.size(); ++i) {
        if (coverage.is_covered(i) || source[i] < 0) continue;
        for (int c = 0; c < 3; ++c) value[3 * i + c] = value[3 * source[i] + c];
        noise[i] = noise[source[i]];
    }
}

void Baker::fill_margin() {
    if (!layout_.lightmap() || settings_.margin <= 0 || layout_.partial()) return;
    copy_margin(layout_.coverage, mesh_, settings_, result_.value.data(), result_.noise.data());
}

void Baker::fill_stats() {
    BakeStats& stats = result_.stats;
    for (const PointLighting& s : shaders_) {
        stats.draws += s.counters.samples;
        stats.rays_traced += s.counters.rays;
        stats.mis_systems += s.counters.systems;
    }
    stats.draws -= std::min(stats.draws, replaced_draws_);  // counts what the values hold
    stats.status = schedule_.status();
    stats.passes = schedule_.passes();
    stats.texels = layout_.count;
    stats.degenerate_uv_triangles = layout_.coverage.degenerate_uv_triangles;
    stats.overlapping_texels = layout_.coverage.overlapping_texels;
    stats.samples_per_texel = stats.covered ? double(stats.samples) / stats.covered : 0;
    stats.draws_per_texel = stats.covered ? double(stats.draws) / stats.covered : 0;
    stats.plan = context_.plan.to_string();
    for (std::size_t k = 0; k < settings_.lighting.techniques.size(); ++k) {
        stats.techniques.push_back(settings_.lighting.techniques[k].name());
        stats.samples_per_round.push_back(settings_.lighting.samples[k]);
    }
    stats.halving = predict_halving(stats.convergence);
    stats.seconds = elapsed();
}

}  // namespace omis::bake_detail

namespace omis {

void fill_bake_margin(const Scene& scene, const BakeSettings& settings, float* value,
                      float* noise) {
    BakeSettings whole = settings;
    whole.first_tile = whole.tile_count = 0;
    bake_detail::validate(scene, whole);
    if (whole.target != BakeTarget::Lightmap || whole.margin <= 0) return;
    const Mesh& mesh = scene.geometry().mesh(whole.mesh);
    bake_detail::copy_margin(rasterize_uv(mesh, whole.width, whole.height), mesh, whole, value,
                             noise);
}

}  // namespace omis
