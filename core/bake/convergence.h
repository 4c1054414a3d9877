// What the next halving of a bake's error costs, from the bake's own measured
// convergence: after each pass the bake records its mean relative error and
// the sampling time so far; error ∝ t^(−β) is fitted over the later passes.
#pragma once

#include <vector>

namespace omis {

// The state of a bake after one of its passes.
struct BakePassRecord {
    double samples_per_texel = 0;    // mean over the baked texels (or corners)
    double seconds = 0;              // sampling time from the first pass's start
    double mean_relative_error = 0;  // the running estimate's, mean over baked texels
};

struct HalvingPrediction {
    double seconds = 0;   // more sampling time to halve the mean error: t·(2^(1/β) − 1)
    double beta = 0.5;    // error ∝ t^(−β); 0.5 (independent draws) when not measured
    int passes_fitted = 0;  // passes the fit used; < 2: not measured, β = 0.5 assumed
    bool measured() const { return passes_fitted >= 2; }
};

// β from a least-squares line through (ln t, ln error) of the later passes (the
// first is skipped: its error comes from one stream's independent-draw formula
// and its time holds the warm-up). Too few usable passes, or an error that does
// not fall, give β = 0.5 with passes_fitted = 0; a fitted β is kept within
// [kMinBeta, kMaxBeta]. t is the last pass's sampling time.
constexpr double kMinBeta = 0.25, kMaxBeta = 1.5;
HalvingPrediction predict_halving(const std::vector<BakePassRecord>& history);

}  // namespace omis
