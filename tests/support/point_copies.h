// T copies of one receiver lit in a single direct_lighting call: every copy
// draws from its own random stream, so the T values are independent
// estimates. Their mean, spread and the estimates' own reported variance
// (green channel), as the statistical tests judge them.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "render/direct_lighting.h"

namespace omis::testing {

struct PointCopies {
    double mean = 0;
    double variance = 0;           // of one copy's value (two passes: stable for near-equal copies)
    double standard_error = 0;     // of the mean: √(variance / T)
    double reported_variance = 0;  // mean over copies of the estimate's own variance
    double reported_sd = 0;        // mean over copies of its square root
    bool finite = true;            // every value and variance finite, variances ≥ 0
    DirectLightingStats stats;
};

// The mean of independent values and its standard error, from their spread.
struct MeanAndError {
    double mean = 0, standard_error = 0;
};
inline MeanAndError mean_and_error(const std::vector<double>& values) {
    const double n = double(values.size());
    MeanAndError m;
    for (double v : values) m.mean += v / n;
    double variance = 0;
    for (double v : values) variance += (v - m.mean) * (v - m.mean) / (n - 1);
    m.standard_error = std::sqrt(variance / n);
    return m;
}

inline PointCopies light_point_copies(const Scene& scene, const Vec3& x, const Vec3& n,
                                      const DirectLightingSettings& settings, int copies) {
    std::vector<double> points, normals, value(3 * std::size_t(copies)),
        variance(3 * std::size_t(copies));
    for (int i = 0; i < copies; ++i) {
        points.insert(points.end(), {x.x, x.y, x.z});
        normals.insert(normals.end(), {n.x, n.y, n.z});
    }
    PointCopies c;
    c.stats = direct_lighting(scene, points.data(), normals.data(), std::size_t(copies), settings,
                              value.data(), variance.data());
    for (int i = 0; i < copies; ++i) {
        const double v = value[3 * i + 1], var = variance[3 * i + 1];
        c.finite = c.finite && std::isfinite(v) && std::isfinite(var) && var >= 0;
        c.mean += v / copies;
        c.reported_variance += var / copies;
        c.reported_sd += std::sqrt(std::max(0.0, var)) / copies;
    }
    for (int i = 0; i < copies; ++i) {
        const double d = value[3 * i + 1] - c.mean;
        c.variance += d * d / (copies - 1);
    }
    c.standard_error = std::sqrt(c.variance / copies);
    return c;
}

}  // namespace omis::testing
