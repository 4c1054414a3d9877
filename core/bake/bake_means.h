// The running means of a bake's points: each pass's estimates join them
// weighted by samples, with the statistics their noise is estimated from.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "bake/bake_layout.h"
#include "bake/convergence.h"

#include "render/direct_lighting.h"

namespace omis::bake_detail {

// Running statistics of one point over passes, beside its running mean (kept
// in the output image itself, weighted by samples): Σ w_p² · own variance_p
// of luminance (the independent-draw formula), the running mean's variance as
// reported, and Σ w_p, w_p the samples of pass p. Doubles: variances of values
// beyond ~1e19 overflow a float.
struct PointState {
    double own_sum = 0;
    double variance = 0;
    double mean_weight = 0;    // Σ w_p: samples, except a tail block's (dyadic_schedule.h)
    std::uint32_t weight = 0;  // samples
    std::uint16_t passes = 0;
    bool done = false;
    // Draws per count a round (PointLighting::draws_per_count): > 1 where the
    // texel's centre sees no light, fixed per texel.
    std::uint8_t draws_per_count = 1;
};

// A point may stop for the noise target only after this many passes: a
// variance estimated from one or two small passes says too little.
constexpr int kMinPassesForNoiseTarget = 3;

// The relative standard error of a running mean (0 before any sample).
double relative_error(const PointState& s, const float* mean);

// One pass over every point that is not done.
struct Pass {
    int first_round = 0, rounds = 0;
    const int* counts = nullptr;  // null: the settings' counts
    std::uint32_t samples = 0;    // per point
    double weight = 0;            // in the running means; 0: samples (a tail block's is less)
    bool tail = false;            // a tail block after a time budget's last net
    const std::vector<DrawnRounds>* earlier = nullptr;  // allocated tiles: their calls so far
};

// A point's estimate of one pass, before it joins the running mean.
struct Shaded {
    std::size_t i;
    double value[3];
    double own_variance;      // luminance, independent-draw formula
    StreamEstimates streams;  // when the bake has several streams
    int draws_per_count;      // PointLighting::draws_per_count
};

// A point's streams over all passes so far: Σ w·estimate and Σ w per stream
// (w: the stream's samples in a pass). Their spread is the error of the
// point's running mean — the passes of one stream continue one sequence, so
// per-pass errors do not add as if independent (that over-stated a noise
// target's error up to 10× and stopped it late).
struct StreamTally {
    double sum[kMaxSampleStreams] = {}, weight[kMaxSampleStreams] = {};
    // Var(mean) = Σ w_s (e_s − ē)² / ((S − 1) W); -1 with fewer than two streams.
    double variance() const {
        double total = 0, mean = 0;
        int used = 0;
        for (int s = 0; s < kMaxSampleStreams; ++s)
            if (weight[s] > 0) {
                total += weight[s];
                mean += sum[s];
                ++used;
            }
        if (used < 2) return -1;
        mean /= total;
        double spread = 0;
        for (int s = 0; s < kMaxSampleStreams; ++s)
            if (weight[s] > 0) {
                const double d = sum[s] / weight[s] - mean;
                spread += weight[s] * d * d;
            }
        return spread / ((used - 1) * total);
    }
};

// The running means of a bake's points and their statistics: the means live
// in the result's values (3 floats a point), the rest here.
class RunningMeans {
public:
    // Uncovered points are never shaded: they count as done for the noise target.
    RunningMeans(const BakeLayout& layout, bool streams, double noise_target,
                 std::vector<float>& values);
    const PointState& state(std::size_t i) const { return state_[i]; }
    bool streams() const { return !tallies_.empty(); }
    void accumulate(const Pass& pass, const std::vector<Shaded>& tile);
    // Every covered point back to no samples; returns the draws they held.
    std::uint64_t forget();
    // Samples and mean relative error over the covered points.
    BakePassRecord record(double seconds, bool tail) const;
    bool noise_target_met() const;

private:
    const BakeLayout& layout_;
    const double noise_target_;
    std::vector<float>& values_;
    std::vector<PointState> state_;
    std::vector<StreamTally> tallies_;  // per point, when the bake has several streams
    tbb::enumerable_thread_specific<std::vector<double>> spread_scratch_;  // accumulate's
};

}  // namespace omis::bake_detail
