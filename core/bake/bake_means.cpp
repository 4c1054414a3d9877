#include "bake/bake_means.h"

#include <algorithm>
#include <cmath>
#include <limits>


namespace omis::bake_detail {

double relative_error(const PointState& s, const float* mean) {
    if (s.weight == 0) return 0;
    const double value = luminance(Vec3(mean[0], mean[1], mean[2]));
    const double var = s.variance;
    if (value <= 0) return var > 0 ? 1.0 : 0.0;
    // A mean beyond the float range of the image has no meaningful noise.
    if (!std::isfinite(value) || !std::isfinite(var)) return std::numeric_limits<double>::infinity();
    return std::sqrt(std::max(0.0, var)) / value;
}

// A tile's points join their running means. Their variance: the
// independent-draw formula over the passes (stable per point, but too high
// for correlated draws); with several streams, scaled by the tile's ratio of
// the streams' spread to it (many degrees of freedom once pooled over the
// tile), or the point's own streams' spread where that is larger.
void RunningMeans::accumulate(const Pass& pass, const std::vector<Shaded>& tile) {
    std::vector<double>& spread = spread_scratch_.local();
    spread.assign(tile.size(), -1);
    double sum_spread = 0, sum_own = 0;
    for (std::size_t t = 0; t < tile.size(); ++t) {
        const Shaded& r = tile[t];
        PointState& s = state_[r.i];
        ++s.passes;
        s.weight += pass.samples;
        s.draws_per_count = std::uint8_t(r.draws_per_count);
        const double w = pass.weight > 0 ? pass.weight : double(pass.samples);
        s.mean_weight += w;
        const double weight = w / s.mean_weight;
        float* mean = &values_[3 * r.i];
        for (int c = 0; c < 3; ++c)  // a mean past the float range stays infinite
            if (!std::isinf(mean[c])) mean[c] += float((r.value[c] - mean[c]) * weight);
        s.own_sum += w * w * r.own_variance;
        s.variance = s.own_sum / (s.mean_weight * s.mean_weight);
        if (tallies_.empty()) continue;
        StreamTally& tally = tallies_[r.i];
        const double per_round = double(pass.samples) / pass.rounds;
        for (int k = 0; k < kMaxSampleStreams; ++k) {
            const double w = r.streams.rounds[k] * per_round;
            tally.sum[k] += w * r.streams.luminance[k];
            tally.weight[k] += w;
        }
        spread[t] = tally.variance();
        if (spread[t] < 0) continue;
        sum_spread += spread[t];
        sum_own += s.variance;
    }
    const double ratio = sum_own > 0 ? sum_spread / sum_own : 1.0;
    for (std::size_t t = 0; t < tile.size(); ++t) {
        PointState& s = state_[tile[t].i];
        // The larger of the two: a tile's ratio comes mostly from its smooth
        // texels, and would understate a texel whose own streams disagree
        // more (rare bright samples, a shadow edge).
        if (spread[t] >= 0) s.variance = std::max(s.variance * ratio, spread[t]);
        // A point whose samples all agreed (nothing seen yet, typically a
        // shadowed texel that rare samples light) gives no error estimate:
        // it is not done, but keeps sampling while others still need to.
        if (noise_target_ > 0 && s.passes >= kMinPassesForNoiseTarget &&
            s.variance > 0 && relative_error(s, &values_[3 * tile[t].i]) <=
                                  noise_target_)
            s.done = true;
    }
}

RunningMeans::RunningMeans(const BakeLayout& layout, bool streams, double noise_target,
                           std::vector<float>& values)
    : layout_(layout), noise_target_(noise_target), values_(values), state_(layout.count),
      tallies_(streams ? layout.count : 0) {
    for (std::size_t i = 0; i < layout_.count; ++i)
        if (!layout_.covered(i)) state_[i].done = true;
}

std::uint64_t RunningMeans::forget() {
    std::uint64_t draws = 0;
    for (std::size_t i = 0; i < layout_.count; ++i) {
        if (!layout_.covered(i)) continue;
        draws += std::uint64_t(state_[i].weight) * state_[i].draws_per_count;
        state_[i] = PointState{};
        if (!tallies_.empty()) tallies_[i] = StreamTally{};
        for (int c = 0; c < 3; ++c) values_[3 * i + c] = 0.f;
    }
    return draws;
}

BakePassRecord RunningMeans::record(double seconds, bool tail) const {
    double sum_error = 0, sum_samples = 0;
    std::size_t covered = 0;
    for (std::size_t i = 0; i < layout_.count; ++i) {
        if (!layout_.covered(i)) continue;
        sum_error += relative_error(state_[i], &values_[3 * i]);
        sum_samples += state_[i].weight;
        ++covered;
    }
    BakePassRecord r;
    r.seconds = seconds;
    r.samples_per_texel = covered ? sum_samples / double(covered) : 0;
    r.mean_relative_error = covered ? sum_error / double(covered) : 0;
    r.tail = tail;
    return r;
}

bool RunningMeans::noise_target_met() const {
    return noise_target_ > 0 &&
           std::all_of(state_.begin(), state_.end(), [&](const PointState& s) {
               return s.done || (s.passes >= kMinPassesForNoiseTarget && s.variance == 0);
           });
}

}  // namespace omis::bake_detail
