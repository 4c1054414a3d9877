#include "bake/bake.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "bake/uv_raster.h"

namespace omis {
namespace {

using Clock = std::chrono::steady_clock;

// One shading point of the bake: a texel centre, a vertex or a corner.
struct BakePoint {
    Vec3 position, normal, geometric_normal;
};

// Texels are processed in square tiles: neighbours share cache lines and
// lights' per-point work, and a tile is the unit of progress and cancel.
constexpr int kTile = 16;

// The shading point at a covered texel, from its triangle and barycentrics
// (computed when shaded rather than stored: 72 bytes a texel otherwise).
BakePoint lightmap_point(const Mesh& mesh, const UvCoverage& cov, std::size_t i, bool smooth) {
    const std::uint32_t t = cov.triangle[i];
    const Vec3 ng = mesh.geometric_normal(t);
    Vec3 n = smooth ? mesh.shading_normal(t, cov.b1[i], cov.b2[i]) : ng;
    if (!(length(n) > 0)) n = ng;
    return {mesh.position(t, cov.b1[i], cov.b2[i]), n, ng};
}

// Vertices take the area-weighted mean of their faces' normals (shading and
// geometric); corners take their own.
std::vector<BakePoint> vertex_points(const Mesh& mesh, bool corners, bool smooth) {
    std::vector<BakePoint> points;
    if (corners) {
        for (std::uint32_t t = 0; t < mesh.num_triangles(); ++t)
            for (int k = 0; k < 3; ++k) {
                const Vec3 ng = mesh.geometric_normal(t);
                const double b1 = k == 1, b2 = k == 2;
                Vec3 n = smooth ? mesh.shading_normal(t, b1, b2) : ng;
                if (!(length(n) > 0)) n = ng;
                points.push_back({mesh.positions[mesh.triangles[t][k]], n, ng});
            }
        return points;
    }
    std::vector<Vec3> sum_n(mesh.positions.size()), sum_ng(mesh.positions.size());
    for (std::uint32_t t = 0; t < mesh.num_triangles(); ++t) {
        const double area = mesh.triangle_area(t);
        const Vec3 ng = mesh.geometric_normal(t);
        for (int k = 0; k < 3; ++k) {
            const double b1 = k == 1, b2 = k == 2;
            const Vec3 n = smooth ? mesh.shading_normal(t, b1, b2) : ng;
            sum_n[mesh.triangles[t][k]] += n * area;
            sum_ng[mesh.triangles[t][k]] += ng * area;
        }
    }
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        const double ln = length(sum_n[v]), lg = length(sum_ng[v]);
        const Vec3 ng = lg > 0 ? sum_ng[v] / lg : Vec3(0, 0, 1);
        points.push_back({mesh.positions[v], ln > 0 ? sum_n[v] / ln : ng, ng});
    }
    return points;
}

// Running statistics of one point over passes, beside its running mean (kept
// in the output image itself, weighted by rounds): Σ rounds_p² · variance_p
// of luminance, and the rounds done. 16 bytes a point: the sum is a double,
// as variances of values beyond ~1e19 overflow a float.
struct PointState {
    double variance_sum = 0;
    std::uint32_t rounds = 0;
    std::uint16_t passes = 0;
    bool done = false;
};

// A point may stop for the noise target only after this many passes: a
// variance estimated from one or two small passes says too little.
constexpr int kMinPassesForNoiseTarget = 3;

double relative_error(const PointState& s, const float* mean) {
    if (s.rounds == 0) return 0;
    const double value = luminance(Vec3(mean[0], mean[1], mean[2]));
    const double var = double(s.variance_sum) / (double(s.rounds) * s.rounds);
    if (value <= 0) return var > 0 ? 1.0 : 0.0;
    // A mean beyond the float range of the image has no meaningful noise.
    if (!std::isfinite(value) || !std::isfinite(var)) return std::numeric_limits<double>::infinity();
    return std::sqrt(std::max(0.0, var)) / value;
}

}  // namespace

const char* bake_status_name(BakeStatus status) {
    switch (status) {
        case BakeStatus::Complete: return "complete";
        case BakeStatus::TimeBudget: return "time budget reached";
        case BakeStatus::NoiseTarget: return "noise target reached";
        case BakeStatus::Cancelled: return "cancelled";
    }
    return "unknown";
}

BakeResult bake(const Scene& scene, const BakeSettings& in, const BakeProgress& progress) {
    if (in.threads < 0) throw std::invalid_argument("threads: must be ≥ 0 (0 = all cores)");
    if (in.threads > 0) {
        // The same bits at any thread count: only the arena's width changes.
        tbb::task_arena arena(in.threads);
        BakeSettings all = in;
        all.threads = 0;
        return arena.execute([&] { return bake(scene, all, progress); });
    }
    const auto start = Clock::now();
    if (!scene.committed())
        throw std::logic_error("scene: not committed (call commit before baking)");
    if (in.mesh >= scene.geometry().num_meshes())
        throw std::invalid_argument("mesh: id " + std::to_string(in.mesh) + " is out of range (" +
                                    std::to_string(scene.geometry().num_meshes()) + " meshes)");
    if (in.margin < 0) throw std::invalid_argument("margin: must not be negative");
    if (in.time_budget < 0 || !std::isfinite(in.time_budget))
        throw std::invalid_argument("time_budget: must be a non-negative number of seconds");
    if (in.noise_target < 0 || !std::isfinite(in.noise_target))
        throw std::invalid_argument("noise_target: must be a non-negative relative error");
    if (in.rounds_per_pass < 1) throw std::invalid_argument("rounds_per_pass: must be ≥ 1");
    const Mesh& mesh = scene.geometry().mesh(in.mesh);

    BakeSettings settings = in;
    if (settings.lighting.techniques.empty())
        default_techniques(scene, settings.lighting.techniques, settings.lighting.samples);

    // Where to shade.
    BakeResult result;
    UvCoverage coverage;
    std::vector<BakePoint> points;  // vertex bakes only
    if (settings.target == BakeTarget::Lightmap) {
        coverage = rasterize_uv(mesh, settings.width, settings.height);
        result.width = settings.width;
        result.height = settings.height;
    } else {
        points = vertex_points(mesh, settings.target == BakeTarget::Corners,
                               settings.smooth_normals);
        result.width = int(points.size());
        result.height = 1;
    }
    const std::size_t count = settings.target == BakeTarget::Lightmap
                                  ? coverage.triangle.size()
                                  : points.size();
    auto covered = [&](std::size_t i) {
        return settings.target != BakeTarget::Lightmap || coverage.is_covered(i);
    };

    // Passes: all rounds at once unless a time or noise budget wants to look
    // between passes; then passes double in size (rounds_per_pass, twice that,
    // ...), so budgets are checked often early on and the per-pass cost (one
    // solve per point) stays small later. Each point's draws continue one
    // low-discrepancy sequence across passes.
    const bool progressive = settings.time_budget > 0 || settings.noise_target > 0;
    const int total_rounds = std::max(1, settings.lighting.rounds);
    std::vector<int> pass_rounds;
    for (int done = 0; done < total_rounds;) {
        const long long doubled = (long long)settings.rounds_per_pass
                                  << std::min<std::size_t>(pass_rounds.size(), 20);
        const int size = progressive ? int(std::min<long long>(total_rounds - done, doubled))
                                     : total_rounds;
        pass_rounds.push_back(size);
        done += size;
    }
    const int max_passes = int(pass_rounds.size());
    LightingContext context(scene, settings.lighting);

    std::vector<PointState> state(count);
    result.value.assign(count * 3, 0.f);  // the running means
    tbb::enumerable_thread_specific<PointLighting> shaders([&] { return PointLighting(context); });
    std::atomic<bool> cancel{false}, out_of_time{false};
    std::mutex report;
    const int tiles_x = settings.target == BakeTarget::Lightmap
                            ? (result.width + kTile - 1) / kTile
                            : int((count + kTile * kTile - 1) / (kTile * kTile));
    const int tiles_y = settings.target == BakeTarget::Lightmap ? (result.height + kTile - 1) / kTile
                                                                : 1;
    const std::size_t tiles = std::size_t(tiles_x) * tiles_y;
    auto tile_points = [&](std::size_t tile, auto&& visit) {
        if (settings.target != BakeTarget::Lightmap) {
            const std::size_t begin = tile * kTile * kTile;
            for (std::size_t i = begin; i < std::min(count, begin + kTile * kTile); ++i) visit(i);
            return;
        }
        const int tx = int(tile % tiles_x), ty = int(tile / tiles_x);
        for (int y = ty * kTile; y < std::min(result.height, (ty + 1) * kTile); ++y)
            for (int x = tx * kTile; x < std::min(result.width, (tx + 1) * kTile); ++x)
                visit(std::size_t(y) * result.width + x);
    };
    auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };

    // Uncovered texels are never shaded: they count as done for the noise target.
    for (std::size_t i = 0; i < count; ++i)
        if (!covered(i)) state[i].done = true;

    // Progress counts shaded points; cancel is checked at every point so a
    // request stops the bake within one point's work.
    std::size_t to_shade = 0;
    for (std::size_t i = 0; i < count; ++i) to_shade += covered(i);
    const double total_work = double(std::max<std::size_t>(1, to_shade)) * total_rounds;
    std::atomic<std::size_t> shaded{0};
    auto report_progress = [&] {
        double fraction = double(shaded.load(std::memory_order_relaxed)) / total_work;
        if (settings.time_budget > 0) fraction = std::max(fraction, elapsed() / settings.time_budget);
        std::unique_lock<std::mutex> lock(report, std::try_to_lock);
        if (lock.owns_lock() && !progress(std::min(1.0, fraction))) cancel = true;
    };

    // Inside a point with huge counts: the same checks, progress at most every 50 ms.
    std::atomic<double> last_report{0};
    context.keep_going = [&] {
        const double now = elapsed();
        if (settings.time_budget > 0 && now >= settings.time_budget) out_of_time = true;
        if (progress && now - last_report.load(std::memory_order_relaxed) >= 0.05) {
            last_report = now;
            report_progress();
        }
        return !cancel.load(std::memory_order_relaxed) && !out_of_time.load(std::memory_order_relaxed);
    };

    int pass = 0;
    BakeStatus status = BakeStatus::Complete;
    for (; pass < max_passes; ++pass) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles, 1),
                          [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t tile = range.begin(); tile != range.end(); ++tile) {
                if (settings.time_budget > 0 && elapsed() >= settings.time_budget)
                    out_of_time = true;
                if (cancel.load(std::memory_order_relaxed) ||
                    out_of_time.load(std::memory_order_relaxed))
                    return;
                PointLighting& shader = shaders.local();
                tile_points(tile, [&](std::size_t i) {
                    PointState& s = state[i];
                    if (!covered(i) || s.done || cancel.load(std::memory_order_relaxed) ||
                        out_of_time.load(std::memory_order_relaxed))
                        return;
                    // Checked per point: a late pass's tile can take longer than the
                    // slack a time budget allows.
                    if (settings.time_budget > 0 && elapsed() >= settings.time_budget) {
                        out_of_time = true;
                        return;
                    }
                    double value[3], variance[3];
                    const BakePoint p = settings.target == BakeTarget::Lightmap
                                            ? lightmap_point(mesh, coverage, i,
                                                             settings.smooth_normals)
                                            : points[i];
                    const int rounds = pass_rounds[pass];
                    try {
                        shader.shade(i, int(s.rounds), rounds, p.position, p.normal,
                                     p.geometric_normal, value, variance);
                    } catch (const LightingCancelled&) {
                        return;
                    }
                    ++s.passes;
                    s.rounds += rounds;
                    const double weight = double(rounds) / s.rounds;
                    float* mean = &result.value[3 * i];
                    for (int c = 0; c < 3; ++c)  // a mean past the float range stays infinite
                        if (!std::isinf(mean[c])) mean[c] += float((value[c] - mean[c]) * weight);
                    s.variance_sum += double(rounds) * rounds *
                                      luminance(Vec3(variance[0], variance[1], variance[2]));
                    if (settings.noise_target > 0 && s.passes >= kMinPassesForNoiseTarget &&
                        relative_error(s, mean) <= settings.noise_target)
                        s.done = true;
                    if (progress && (shaded.fetch_add(rounds, std::memory_order_relaxed) % 64) < std::size_t(rounds))
                        report_progress();
                });
            }
        });
        if (cancel) {
            status = BakeStatus::Cancelled;
            break;
        }
        if (out_of_time) {
            status = BakeStatus::TimeBudget;
            ++pass;  // the interrupted pass counts
            break;
        }
        if (settings.noise_target > 0 &&
            std::all_of(state.begin(), state.end(), [&](const PointState& s) { return s.done; })) {
            status = BakeStatus::NoiseTarget;
            ++pass;
            break;
        }
    }

    // Outputs, then the margin around UV islands.
    result.noise.assign(count, 0.f);
    result.mask.assign(count, 0.f);
    BakeStats& stats = result.stats;
    double sum_error = 0, sum_passes = 0;
    std::size_t n_covered = 0;
    for (std::size_t i = 0; i < count; ++i) {
        if (!covered(i)) continue;
        const PointState& s = state[i];
        const double err = relative_error(s, &result.value[3 * i]);
        result.noise[i] = float(err);
        result.mask[i] = 1.f;
        sum_error += err;
        sum_passes += s.passes;
        stats.max_relative_error = std::max(stats.max_relative_error, err);
        ++n_covered;
    }
    if (settings.target == BakeTarget::Lightmap && settings.margin > 0) {
        const std::vector<std::int64_t> source = margin_sources(coverage, settings.margin);
        for (std::size_t i = 0; i < count; ++i) {
            if (coverage.is_covered(i) || source[i] < 0) continue;
            for (int c = 0; c < 3; ++c) result.value[3 * i + c] = result.value[3 * source[i] + c];
            result.noise[i] = result.noise[source[i]];
        }
    }

    for (const PointLighting& s : shaders) {
        stats.samples += s.counters.samples;
        stats.rays_traced += s.counters.rays;
        stats.mis_systems += s.counters.systems;
    }
    stats.status = status;
    stats.passes = pass;
    stats.texels = count;
    stats.covered = n_covered;
    stats.degenerate_uv_triangles = coverage.degenerate_uv_triangles;
    stats.overlapping_texels = coverage.overlapping_texels;
    stats.mean_relative_error = n_covered ? sum_error / n_covered : 0;
    stats.samples_per_texel = n_covered ? double(stats.samples) / n_covered : 0;
    stats.passes_per_texel = n_covered ? sum_passes / n_covered : 0;
    stats.plan = context.plan.to_string();
    for (std::size_t k = 0; k < settings.lighting.techniques.size(); ++k) {
        stats.techniques.push_back(settings.lighting.techniques[k].name());
        stats.samples_per_round.push_back(settings.lighting.samples[k]);
    }
    stats.seconds = elapsed();
    return result;
}

}  // namespace omis
