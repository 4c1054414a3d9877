// Where each technique's draws stand: its sequences and draw starts
// (technique_draws.h), and selector draws made ahead of their samples.
#include "render/technique_draws.h"

#include <stdexcept>
#include <string>

#include "render/point_lighting_impl.h"

namespace omis {

// Each table technique's counts among a point's kept ones: a count per
// stream and integrated light (LightingContext::keep_draw_counts' layout).
TechniqueDraws::TechniqueDraws(const LightingContext& context)
    : context_(context),
      kept_counts_at_(table_technique_offsets(
          context, std::size_t(context.settings.streams) * context.integrated.size())) {}

void TechniqueDraws::begin_point(std::uint64_t base, int first_round,
                                 const std::vector<DrawnRounds>* earlier, int draws_per_count) {
    const std::size_t K = std::size_t(context_.settings.streams);
    base_ = base;
    forget_sequences(sequences_, (context_.settings.techniques.size() + 1) * K);
    set_starts(first_round, earlier);
    if (draws_per_count > 1)
        for (std::uint32_t& start : starts_) start *= std::uint32_t(draws_per_count);
}

void TechniqueDraws::set_starts(int first_round, const std::vector<DrawnRounds>* earlier) {
    const int K = context_.settings.streams;
    const std::vector<int>& samples = context_.settings.samples;
    starts_.assign(samples.size() * K, 0);
    if (!earlier) {
        for (std::size_t k = 0; k < samples.size(); ++k)
            for (int s = 0; s < K; ++s)
                starts_[k * K + s] = std::uint32_t(rounds_in_stream(s, first_round, K) * samples[k]);
        return;
    }
    int next = 0;
    for (const DrawnRounds& d : *earlier) {
        if (d.first_round != next || d.rounds < 0)
            throw std::invalid_argument("earlier: calls must follow each other from round 0");
        const int* counts = d.counts ? d.counts : samples.data();
        for (std::size_t k = 0; k < samples.size(); ++k)
            for (int s = 0; s < K; ++s)
                starts_[k * K + s] += std::uint32_t(
                    counts[k] * (rounds_in_stream(s, d.first_round + d.rounds, K) -
                                 rounds_in_stream(s, d.first_round, K)));
        next += d.rounds;
    }
    if (next != first_round)
        throw std::invalid_argument("earlier: rounds add up to " + std::to_string(next) +
                                    ", not first_round " + std::to_string(first_round));
}


// The selection takes u1 of the shape's pair, and the shape its rest within
// the chosen light's share (SelectedLight::rest), as Cycles does: the draws
// that choose one light then keep the pair's 2-D stratification, where an
// independent selection dimension left each light a random subset of it.
// Group 1 fills u1's bits below its 32 (u1 then uniform on [0, 1) and its
// rest keeps them). Measured per sample on the emissive_mesh race scene (the
// sphere hiding part of the square light): relMSE 0.74×, 0.54×, 0.34× at 16,
// 64, 256 samples, most in the penumbra (bench/results/error_sources.txt,
// 2026-12-01).
void PointLighting::Impl::begin_selector_draw(int k, const ScrambledSobol& sequence,
                                              std::uint32_t index, const SurfacePoint& centre,
                                              const Footprint* footprint, SelectorDraw& d) {
    d.k = k;
    d.sequence = &sequence;
    d.index = index;
    d.selector = technique_selectors_[k];
    if (footprint) {
        double fu, fv;
        sequence.get_2d(index, 0, fu, fv);
        d.p = footprint->at(fu, fv);
    } else {
        d.p = centre;
    }
    sequence.get_2d(index, 2, d.u1, d.u2);
    LightSelector::Memo* memo;
    const LightSelector::Receiver at = receiver_at(d.p.x, d.p.n, memo);
    d.partial = d.selector->begin_draw(at, d.u1 + sequence.get_1d(index, 1) * 0x1.0p-32, memo);
    d.finished = false;
}

void PointLighting::Impl::finish_selector_draw(SelectorDraw& d) {
    if (d.finished) return;
    d.finished = true;
    d.light = d.selector->finish_draw(d.partial);
    if (d.light) d.u1 = d.light->rest;
}


}  // namespace omis
