// Where each technique's draws come from at a point: one Owen-scrambled
// Sobol' sequence per technique and randomisation stream (settings.streams),
// seeded from the point, and where a call's draws start in each (after the
// earlier calls' rounds); and, for the light techniques that draw from a
// per-point table, each table light's own sequence (LightSequences).
// Internal to the lighting core (render/*.cpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "math/random.h"
#include "render/light_tables.h"
#include "sampling/sequence.h"

namespace omis {

// `count` sequences, none made yet: clears only their flags (assigning
// nullopt copied whole ~100-byte objects, ~5 % of a later pass's repeated
// work).
inline void forget_sequences(std::vector<std::optional<ScrambledSobol>>& sequences,
                             std::size_t count) {
    sequences.resize(count);
    for (std::optional<ScrambledSobol>& s : sequences) s.reset();
}

// A light drawn from a per-point table before the sample (LightSequences):
// its slot in the table, its shape point and its footprint position.
struct TableDraw {
    int slot = -1;  // -1: take_sample selects (bsdf, selectors)
    double u1 = 0, u2 = 0;
    double fu = 0, fv = 0;
};

class TechniqueDraws {
public:
    explicit TechniqueDraws(const LightingContext& context);

    // A point's draws: sequences seeded from `base` (the point's seed), and
    // each technique's first draw of rounds [first_round, …) in each stream —
    // after those of the earlier calls, whose counts may differ from the
    // settings' (sample allocation, issue 10) — times draws_per_count
    // (a shadowed texel's, DirectLightingSettings::shadowed_draws).
    void begin_point(std::uint64_t base, int first_round, const std::vector<DrawnRounds>* earlier,
                     int draws_per_count);
    // Technique k's sequence of stream s; k = techniques.size(): the delta
    // lights' (a position per round). Made at its first use in a call, not at
    // every round or by every user — its seed hashes were ~190 of a sample's
    // ~5,150 instructions on an emission_world-like bake (callgrind).
    const ScrambledSobol& sequence(std::size_t k, int s) {
        const std::size_t K = std::size_t(context_.settings.streams);
        std::optional<ScrambledSobol>& built = sequences_[k * K + std::size_t(s)];
        if (!built) built.emplace(base_ ^ mix64(std::uint64_t(k) * K + std::uint64_t(s) + 1));
        return *built;
    }
    // Technique k's first draw of the call in stream s.
    std::uint32_t start(int k, int s) const {
        return starts_[std::size_t(k) * std::size_t(context_.settings.streams) + std::size_t(s)];
    }
    // Rounds of stream s (of K) among rounds [0, end_round).
    static int rounds_in_stream(int s, int end_round, int K) {
        return end_round > s ? (end_round - s + K - 1) / K : 0;
    }

private:
    friend class LightSequences;
    void set_starts(int first_round, const std::vector<DrawnRounds>* earlier);

    const LightingContext& context_;
    std::uint64_t base_ = 0;  // the point's
    std::vector<std::optional<ScrambledSobol>> sequences_;  // per technique and stream
    std::vector<std::uint32_t> starts_;                     // per technique and stream
    // LightSequences' storage, kept from point to point (no allocation per
    // point and pass): per technique, stream and table slot, the draws taken
    // and the slot's own sequence once made.
    std::vector<std::uint32_t> taken_scratch_;
    std::vector<std::optional<ScrambledSobol>> sequences_scratch_;
    // Per table technique, the offset of its counts among a point's kept
    // ones (LightingContext::draw_counts); ~0 for the others.
    std::vector<std::size_t> kept_counts_at_;
};

// Per-light sample streams for the light techniques that draw from a
// per-point table: the table picks a light by the technique sequence's
// selection dimension, and the light's shape point is the next unused point
// of that light's OWN scrambled sequence (per technique, stream and light).
// Each light's draws then form a stratified prefix whatever its share — a
// strip of one shared net is stratified only for dyadic shares, and a shape
// taken from an unrelated dimension not at all. The draw's footprint
// position comes from the same point of that sequence: one 4-D Sobol' point
// (ScrambledSobol::get_4d), the shape from dimensions 0–1 (a (0,2)-net), the
// position from 2–3, all four a (3,m,4)-net, so a light's draws are
// stratified in position and light point together. That matters in a
// penumbra, where visibility depends on both. On a penumbra texel lit by two
// lights (tests/core/test_footprint_strata.cpp), the variance at 256 samples
// over one sample's: positions from the technique's sequence 1/680; from the
// light's sequence as a second 2-D pair, shuffled apart (padding) 1/1400;
// the 4-D point 1/4860. On the demo room's 128² floor (4.7 cm texels),
// relMSE at 256 equal samples against Cycles' (3 seeds): 1.03 → 0.66, its
// penumbrae (edge texels) 0.97 → 0.57; shared_image (1.6 cm texels) 0.99 →
// 0.93 (issue 9; bench/results/error_sources.txt). Unbiased: a light's sequence
// is independent of the selections, so its next point is uniform whatever
// the count, in position as in shape. A later pass continues every count:
// the table is the same at every pass, so the counts are those the point's
// last call left (LightingContext::draw_counts, where kept), else the
// selections of earlier rounds are replayed (cheap per draw: no rays, one
// table lookup each; but every pass replays them all).
class LightSequences {
public:
    // active_lights: the point's light techniques; tables: their tables at the point.
    LightSequences(TechniqueDraws& draws, const LightTables& tables, std::uint64_t point,
                   const std::vector<int>& active_lights)
        : draws_(draws), tables_(tables), context_(draws.context_), base_(draws.base_),
          lights_(tables.longest()), streams_(context_.settings.streams),
          taken_(draws.taken_scratch_), sequences_(draws.sequences_scratch_),
          kept_(context_.draw_counts.of(point)), active_lights_(active_lights) {
        const auto& techniques = context_.settings.techniques;
        // Counts only where a technique draws from a table: zeroing them per
        // point for 16k tree-drawn lights cost 40 % of an emissive mesh's bake.
        if (std::none_of(active_lights.begin(), active_lights.end(),
                         [&](int k) { return uses_table(k); }))
            return;
        taken_.assign(techniques.size() * std::size_t(streams_) * lights_, 0);
        forget_sequences(sequences_, taken_.size());
        for (int k : active_lights) {
            if (!uses_table(k)) continue;
            for (int s = 0; s < streams_; ++s) {
                const std::uint32_t start = draws.start(k, s);
                if (start == 0) continue;  // a first pass: nothing to count
                const ScrambledSobol& seq = draws.sequence(std::size_t(k), s);
                for (std::uint32_t i = restore(k, s, start); i < start; ++i)
                    ++count(k, s, slot(k, seq, i));
            }
        }
    }
    bool uses_table(int k) const {
        return draws_.kept_counts_at_[std::size_t(k)] != ~std::size_t(0);
    }
    // Leaves the counts for the point's next call (after all of this one's draws).
    void keep() const {
        if (!kept_) return;
        for (int k : active_lights_)
            if (uses_table(k))
                for (int s = 0; s < streams_; ++s) {
                    std::uint32_t* to = kept(k, s);
                    const std::size_t n = table_size(k);
                    for (std::size_t i = 0; i < n; ++i) to[i] = taken_[cell(k, s, int(i))];
                }
    }
    // Technique k's draw `index` of stream s: its light and shape point.
    TableDraw draw(int k, int s, const ScrambledSobol& seq, std::uint32_t index) {
        TableDraw d;
        d.slot = slot(k, seq, index);
        const std::size_t at = cell(k, s, d.slot);
        std::optional<ScrambledSobol>& light_sequence = sequences_[at];
        if (!light_sequence) {  // made at its light's first draw of the point
            const std::uint64_t id = (std::uint64_t(k) * streams_ + std::uint64_t(s)) << 32 |
                                     std::uint64_t(d.slot + 1);
            light_sequence.emplace(base_ ^ mix64(0x6a09e667f3bcc909ull ^ id));
        }
        double u[4];
        light_sequence->get_4d(taken_[at]++, 0, u);
        d.u1 = u[0];
        d.u2 = u[1];
        d.fu = u[2];
        d.fv = u[3];
        return d;
    }

private:
    // Technique k's kept counts of stream s (a slot per integrated light).
    std::uint32_t* kept(int k, int s) const {
        const std::size_t lights = context_.integrated.size();
        return kept_ + draws_.kept_counts_at_[std::size_t(k)] + std::size_t(s) * lights;
    }
    std::size_t table_size(int k) const {
        return std::min(tables_[k].lights.size(), context_.integrated.size());
    }
    // The kept counts of technique k's stream s, where they count no more
    // than the `start` draws before this call (then a prefix of them): how
    // many they count, from which the rest are counted. 0 where none are kept.
    std::uint32_t restore(int k, int s, std::uint32_t start) {
        if (!kept_) return 0;
        const std::uint32_t* from = kept(k, s);
        const std::size_t n = table_size(k);
        std::uint64_t counted = 0;
        for (std::size_t i = 0; i < n; ++i) counted += from[i];
        if (counted > start) return 0;  // ahead of this call (a probe's): count afresh
        for (std::size_t i = 0; i < n; ++i) count(k, s, int(i)) = from[i];
        return std::uint32_t(counted);
    }
    int slot(int k, const ScrambledSobol& seq, std::uint32_t index) const {
        return tables_[k].slot(seq.get_1d(index, 1));
    }
    std::size_t cell(int k, int s, int slot) const {
        return (std::size_t(k) * streams_ + std::size_t(s)) * lights_ + std::size_t(slot);
    }
    std::uint32_t& count(int k, int s, int slot) { return taken_[cell(k, s, slot)]; }
    TechniqueDraws& draws_;
    const LightTables& tables_;
    const LightingContext& context_;
    std::uint64_t base_;
    // The longest table's size, not the scene's light count: the counts are
    // cleared per point, and a scene of many emitter triangles (drawn through
    // the light tree, no table) would otherwise clear a vector that long at
    // every point and pass (16k triangles: ~0.4 s per pass at 128²).
    std::size_t lights_;
    int streams_;
    std::vector<std::uint32_t>& taken_;  // per technique, stream and table slot
    std::vector<std::optional<ScrambledSobol>>& sequences_;  // each slot's own, per cell
    std::uint32_t* kept_;  // the point's kept counts, or null
    const std::vector<int>& active_lights_;
};

}  // namespace omis
