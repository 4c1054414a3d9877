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
    // A time budget's tail block (bake/dyadic_schedule.h): it joins the net's
    // mean at a reduced weight, so its error does not follow the rate of the
    // passes before it; the fit leaves it out.
    bool tail = false;
};

struct HalvingPrediction {
    double seconds = 0;   // more sampling time to halve the mean error: t·(2^(1/β) − 1)
    double beta = 0.5;    // error ∝ t^(−β); 0.5 (independent draws) when not measured
    int passes_fitted = 0;  // passes the fit used; < 2: not measured, β = 0.5 assumed
    bool measured() const { return passes_fitted >= 2; }
};

// β from a least-squares line through (ln t, ln error) of the last passes (at
// most four; the first pass only when there are just two: its time holds the
// warm-up, and a one-round first pass's error comes from the independent-draw
// formula; tail blocks never). Fewer than two usable passes, passes too close
// in time or samples (< 1.25× apart, < 1.5×), or an error that does not fall
// give β = 0.5 with
// passes_fitted = 0; a fitted β is kept within [kMinBeta, kMaxBeta]. t is the
// last pass's sampling time.
constexpr double kMinBeta = 0.25, kMaxBeta = 1.5;
HalvingPrediction predict_halving(const std::vector<BakePassRecord>& history);

}  // namespace omis
