// Discrete distributions from weights: the probabilities and CDF every light
// table and light selector draws from.
#pragma once

#include <algorithm>
#include <vector>

namespace omis {

// Weights made a probability (each weight that is not positive — NaN too —
// first given a tiny share, 1e-9 of the largest, so every direction the
// integrand covers stays sampleable; 1 where none is positive), and the CDF
// of probabilities (running sums, its end exactly 1; empty for none). One
// rule for every light table and selector.
inline void normalise_weights(std::vector<double>& weights) {
    double largest = 0, total = 0;
    for (double w : weights) largest = std::max(largest, w);
    for (double& w : weights) {
        if (!(w > 0)) w = largest > 0 ? 1e-9 * largest : 1.0;
        total += w;
    }
    for (double& w : weights) w /= total;
}
inline void cumulate(const std::vector<double>& probability, std::vector<double>& cdf) {
    cdf.clear();
    double running = 0;
    for (double w : probability) cdf.push_back(running += w);
    if (!cdf.empty()) cdf.back() = 1.0;
}

}  // namespace omis
