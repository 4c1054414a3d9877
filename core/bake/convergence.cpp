#include "bake/convergence.h"

#include <algorithm>
#include <cmath>

namespace omis {
namespace {

// The fit uses at most this many of the last passes: passes double in size, so
// four span ~8× the samples, and older passes (dominated by warm-up and by the
// first pass's error formula) say less about the rate now.
constexpr std::size_t kMaxFitted = 4;
// Below these spreads of time and samples the slope is mostly timing jitter
// (e.g. a sample budget's last round, a pass of its own, adds little).
constexpr double kMinTimeSpan = 1.25, kMinSamplesSpan = 1.5;

}  // namespace

HalvingPrediction predict_halving(const std::vector<BakePassRecord>& history) {
    HalvingPrediction p;
    const double t = history.empty() ? 0.0 : std::max(0.0, history.back().seconds);
    std::vector<BakePassRecord> used, passes;
    for (const BakePassRecord& r : history)
        if (!r.tail) passes.push_back(r);
    // The first pass only when there are just two.
    const std::size_t n = passes.size();
    const std::size_t first = n <= 2 ? 0 : std::max<std::size_t>(1, n > kMaxFitted ? n - kMaxFitted : 1);
    for (std::size_t i = first; i < n; ++i) {
        const BakePassRecord& r = passes[i];
        const bool usable = r.seconds > 0 && std::isfinite(r.seconds) &&
                            r.mean_relative_error > 0 && std::isfinite(r.mean_relative_error) &&
                            (used.empty() || r.seconds > used.back().seconds);
        if (usable) used.push_back(r);
    }
    if (used.size() >= 2 && used.back().seconds >= kMinTimeSpan * used.front().seconds &&
        used.back().samples_per_texel >= kMinSamplesSpan * used.front().samples_per_texel &&
        used.front().samples_per_texel > 0) {
        double mx = 0, my = 0;
        for (const BakePassRecord& r : used) {
            mx += std::log(r.seconds);
            my += std::log(r.mean_relative_error);
        }
        mx /= double(used.size());
        my /= double(used.size());
        double sxy = 0, sxx = 0;
        for (const BakePassRecord& r : used) {
            const double dx = std::log(r.seconds) - mx;
            sxy += dx * (std::log(r.mean_relative_error) - my);
            sxx += dx * dx;
        }
        const double beta = -sxy / sxx;
        // An error that does not fall measurably has no halving time to predict.
        if (std::isfinite(beta) && beta > 0.05) {
            p.beta = std::clamp(beta, kMinBeta, kMaxBeta);
            p.passes_fitted = int(used.size());
        }
    }
    p.seconds = t * (std::pow(2.0, 1.0 / p.beta) - 1.0);
    return p;
}

}  // namespace omis
