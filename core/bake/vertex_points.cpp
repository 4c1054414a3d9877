#include "bake/vertex_points.h"

#include <algorithm>
#include <cmath>

namespace omis {

CornerPoint inset_corner(const Mesh& mesh, std::uint32_t t, int k) {
    // Cycles' constants ("empirically determined"): a position offset relative
    // to the coordinates' size, and a margin on every barycentric.
    constexpr double kPositionOffset = 1e-4, kBarycentricMargin = 1e-5;
    const auto v = mesh.triangle_vertices(t);
    CornerPoint corner;
    corner.b1 = k == 1;
    corner.b2 = k == 2;
    const Vec3 p = v[k];
    const Vec3 to_center = (v[0] + v[1] + v[2]) / 3.0 - p;
    const double distance = length(to_center);
    if (!(distance > 0)) return corner;
    const double size = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z), 1.0});
    const Vec3 q = p + to_center * (std::min(distance, size * kPositionOffset) / distance);

    // Barycentrics of q by least squares on the triangle's plane.
    const Vec3 e1 = v[1] - v[0], e2 = v[2] - v[0], d = q - v[0];
    const double d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    const double denom = d11 * d22 - d12 * d12;
    if (!(denom > 0)) return corner;
    const double lo = kBarycentricMargin, hi = 1 - kBarycentricMargin;
    const double w1 = std::clamp((d22 * dot(d, e1) - d12 * dot(d, e2)) / denom, lo, hi);
    const double w2 = std::clamp((d11 * dot(d, e2) - d12 * dot(d, e1)) / denom, lo, hi);
    const double w0 = std::clamp(1 - w1 - w2, lo, hi);
    // As Cycles: vertex 0 and 1 keep their clamped weights, vertex 2 the rest.
    corner.b1 = w1;
    corner.b2 = 1 - w0 - w1;
    return corner;
}

BakeResult corners_to_vertices(const Mesh& mesh, BakeResult corners) {
    const std::size_t nv = mesh.positions.size();
    BakeResult out;
    out.width = int(nv);
    out.height = 1;
    out.value.assign(3 * nv, 0.f);
    out.noise.assign(nv, 0.f);
    out.mask.assign(nv, 0.f);
    out.samples.assign(nv, 0);  // a vertex has taken the samples of all its corners
    std::vector<double> sum(3 * nv, 0.0), var(nv, 0.0);
    std::vector<int> count(nv, 0);
    for (std::uint32_t t = 0; t < mesh.num_triangles(); ++t)
        for (int k = 0; k < 3; ++k) {
            const std::size_t c = 3 * std::size_t(t) + k, v = mesh.triangles[t][k];
            if (corners.mask[c] <= 0) continue;
            const float* rgb = &corners.value[3 * c];
            for (int ch = 0; ch < 3; ++ch) sum[3 * v + ch] += rgb[ch];
            // A corner whose mean overflowed the float range (infinite) has no
            // meaningful spread: 0 there, not 0 × ∞.
            const double lum = luminance(Vec3(rgb[0], rgb[1], rgb[2]));
            const double sd = std::isfinite(lum) ? double(corners.noise[c]) * lum : 0.0;
            var[v] += sd * sd;
            ++count[v];
            if (c < corners.samples.size()) out.samples[v] += corners.samples[c];
        }
    BakeStats& stats = corners.stats;
    double sum_error = 0;
    std::size_t covered = 0;
    stats.max_relative_error = 0;
    for (std::size_t v = 0; v < nv; ++v) {
        if (count[v] == 0) continue;
        const Vec3 mean(sum[3 * v] / count[v], sum[3 * v + 1] / count[v],
                        sum[3 * v + 2] / count[v]);
        for (int ch = 0; ch < 3; ++ch) out.value[3 * v + ch] = float(mean[ch]);
        const double value = luminance(mean), sd = std::sqrt(var[v]) / count[v];
        const double err = value > 0 ? sd / value : (sd > 0 ? 1.0 : 0.0);
        out.noise[v] = float(err);
        out.mask[v] = 1.f;
        sum_error += err;
        stats.max_relative_error = std::max(stats.max_relative_error, err);
        ++covered;
    }
    stats.texels = nv;
    stats.covered = covered;
    stats.mean_relative_error = covered ? sum_error / covered : 0;
    stats.samples_per_texel = covered ? double(stats.samples) / covered : 0;
    stats.draws_per_texel = covered ? double(stats.draws) / covered : 0;
    out.stats = stats;
    return out;
}

}  // namespace omis
