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
#include "bake/vertex_points.h"

namespace omis {
namespace {

using Clock = std::chrono::steady_clock;

// Texels are processed in square tiles: neighbours share cache lines and
// lights' per-point work, and a tile is the unit of progress and cancel.
constexpr int kTile = 16;

// A covered texel's footprint as a Footprint: positions and normals at the
// barycentrics of texel_footprint (uv_raster.h).
class TexelFootprint final : public Footprint {
public:
    TexelFootprint(const Mesh& mesh, const UvCoverage& cov, std::size_t i, bool smooth)
        : mesh_(mesh), map_(mesh, cov, i), ng_(mesh.geometric_normal(map_.triangle())),
          smooth_(smooth) {}

    SurfacePoint at(double u, double v) const override {
        const auto b = map_.barycentrics(u, v);
        return point(b[0], b[1]);
    }
    SurfacePoint centre() const { return at(0.5, 0.5); }

private:
    SurfacePoint point(double b1, double b2) const {
        const std::uint32_t t = map_.triangle();
        Vec3 n = smooth_ ? mesh_.shading_normal(t, b1, b2) : ng_;
        if (!(length(n) > 0)) n = ng_;
        return {mesh_.position(t, b1, b2), n, ng_};
    }

    const Mesh& mesh_;
    TexelFootprintMap map_;
    Vec3 ng_;
    bool smooth_;
};

// One point per triangle corner, inside its triangle as Cycles places it
// (vertex bakes are reduced from corners: see vertex_points.h).
std::vector<SurfacePoint> corner_points(const Mesh& mesh, bool smooth) {
    std::vector<SurfacePoint> points;
    for (std::uint32_t t = 0; t < mesh.num_triangles(); ++t)
        for (int k = 0; k < 3; ++k) {
            const Vec3 ng = mesh.geometric_normal(t);
            const CornerPoint c = inset_corner(mesh, t, k);
            Vec3 n = smooth ? mesh.shading_normal(t, c.b1, c.b2) : ng;
            if (!(length(n) > 0)) n = ng;
            points.push_back({mesh.position(t, c.b1, c.b2), n, ng});
        }
    return points;
}

// Running statistics of one point over passes, beside its running mean (kept
// in the output image itself, weighted by samples): Σ w_p² · variance_p of
// luminance and Σ w_p, w_p the samples of pass p. 16 bytes a point: the sum is
// a double, as variances of values beyond ~1e19 overflow a float.
struct PointState {
    double variance_sum = 0;
    std::uint32_t weight = 0;
    std::uint16_t passes = 0;
    bool done = false;
};

// A point may stop for the noise target only after this many passes: a
// variance estimated from one or two small passes says too little.
constexpr int kMinPassesForNoiseTarget = 3;

double relative_error(const PointState& s, const float* mean) {
    if (s.weight == 0) return 0;
    const double value = luminance(Vec3(mean[0], mean[1], mean[2]));
    const double var = double(s.variance_sum) / (double(s.weight) * s.weight);
    if (value <= 0) return var > 0 ? 1.0 : 0.0;
    // A mean beyond the float range of the image has no meaningful noise.
    if (!std::isfinite(value) || !std::isfinite(var)) return std::numeric_limits<double>::infinity();
    return std::sqrt(std::max(0.0, var)) / value;
}

// How a sample budget splits into rounds: whole rounds of the settings'
// counts (P samples a round), then — when P does not divide the budget N — one
// final round holding P + (N mod P) samples, the extra spread over the
// techniques in proportion to their counts. Every technique keeps at least its
// own count in that round, so the combination there covers what it covers
// elsewhere and stays unbiased. A budget below P takes one whole round.
struct SampleBudget {
    int per_round = 0;
    int full_rounds = 1;
    std::vector<int> last;  // counts of the final round; empty: none
    int last_samples = 0;
};

SampleBudget plan_samples(const LightingContext& context, long long samples, int rounds) {
    SampleBudget b;
    const std::vector<int>& counts = context.settings.samples;
    for (int k : context.techniques) b.per_round += counts[k];
    if (b.per_round <= 0) {
        // Delta lights only (or nothing): a round is one evaluation of them at
        // one position of the footprint, and counts as one sample.
        b.per_round = 1;
        b.full_rounds = int(std::clamp<long long>(samples > 0 ? samples : rounds, 1, 1LL << 30));
        return b;
    }
    if (samples <= 0) {
        b.full_rounds = std::max(1, rounds);
        return b;
    }
    const long long P = b.per_round;
    const long long whole = std::max(1LL, samples / P), rest = samples >= P ? samples % P : 0;
    b.full_rounds = int(std::min<long long>(whole, 1LL << 30));
    if (rest == 0) return b;
    b.full_rounds -= 1;
    b.last = counts;
    long long given = 0;
    for (int k : context.techniques) {
        const long long extra = rest * counts[k] / P;
        b.last[k] += int(extra);
        given += extra;
    }
    for (int k : context.techniques)
        if (given < rest && counts[k] > 0) {
            ++b.last[k];
            ++given;
        }
    b.last_samples = int(P + rest);
    return b;
}

// Predicts a pass's duration from the passes so far as a + b·samples (a: the
// fixed cost of a pass — solves, thread wake-up), through the last two passes
// of different sizes, else in proportion to the last one.
class PassTimer {
public:
    void add(double samples, double seconds) {
        if (n_ > 0 && samples != s_[1]) {
            s_[0] = s_[1];
            t_[0] = t_[1];
        }
        s_[1] = samples;
        t_[1] = seconds;
        ++n_;
    }
    // The most samples per point a pass can take in `seconds`.
    double fit(double seconds) const {
        if (n_ == 0 || !(s_[1] > 0)) return 0;
        double b = t_[1] / s_[1], a = 0;
        if (n_ > 1 && s_[0] != s_[1] && s_[0] > 0) {
            const double slope = (t_[1] - t_[0]) / (s_[1] - s_[0]);
            if (slope > 0) {
                b = slope;
                a = std::max(0.0, t_[1] - b * s_[1]);
            }
        }
        return b > 0 ? (seconds - a) / b : 0;
    }

private:
    double s_[2] = {0, 0}, t_[2] = {0, 0};
    int n_ = 0;
};

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
    if (in.target == BakeTarget::Vertices && scene.committed() &&
        in.mesh < scene.geometry().num_meshes()) {
        // A vertex is the mean of its corners, as in Cycles (vertex_points.h).
        BakeSettings corners = in;
        corners.target = BakeTarget::Corners;
        return corners_to_vertices(scene.geometry().mesh(in.mesh), bake(scene, corners, progress));
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
    std::vector<SurfacePoint> points;  // vertex bakes only
    if (settings.target == BakeTarget::Lightmap) {
        coverage = rasterize_uv(mesh, settings.width, settings.height);
        result.width = settings.width;
        result.height = settings.height;
    } else {
        points = corner_points(mesh, settings.smooth_normals);
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
    // solve per point) stays small later. Every pass reaches every point: a
    // time budget ends on whole passes (the first always completes; the last
    // shrinks to what the measured cost says fits), so all points end with the
    // same count. Each point's draws continue one low-discrepancy sequence
    // across passes.
    const bool progressive = settings.time_budget > 0 || settings.noise_target > 0;
    settings.lighting.receiver = scene.mesh_receiver(in.mesh);  // render/receiver.h
    LightingContext context(scene, settings.lighting);
    const SampleBudget budget = plan_samples(context, settings.samples, settings.lighting.rounds);
    const long long samples_per_point =
        (long long)budget.full_rounds * budget.per_round + budget.last_samples;

    std::vector<PointState> state(count);
    result.value.assign(count * 3, 0.f);  // the running means
    tbb::enumerable_thread_specific<PointLighting> shaders([&] { return PointLighting(context); });
    std::atomic<bool> cancel{false};
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

    // Progress counts shaded samples; cancel is checked at every point so a
    // request stops the bake within one point's work.
    std::size_t to_shade = 0;
    for (std::size_t i = 0; i < count; ++i) to_shade += covered(i);
    const double total_work = double(std::max<std::size_t>(1, to_shade)) *
                              double(std::max<long long>(1, samples_per_point));
    std::atomic<std::size_t> shaded{0};
    auto report_progress = [&] {
        double fraction = double(shaded.load(std::memory_order_relaxed)) / total_work;
        if (settings.time_budget > 0) fraction = std::max(fraction, elapsed() / settings.time_budget);
        std::unique_lock<std::mutex> lock(report, std::try_to_lock);
        if (lock.owns_lock() && !progress(std::min(1.0, fraction))) cancel = true;
    };

    // Inside a point with huge counts: the cancel check, and progress at most
    // every 50 ms (time budgets end on whole passes, never inside a point).
    std::atomic<double> last_report{0};
    context.keep_going = [&] {
        const double now = elapsed();
        if (progress && now - last_report.load(std::memory_order_relaxed) >= 0.05) {
            last_report = now;
            report_progress();
        }
        return !cancel.load(std::memory_order_relaxed);
    };

    // One pass over every point that is not done.
    struct Pass {
        int first_round = 0, rounds = 0;
        const int* counts = nullptr;  // null: the settings' counts
        std::uint32_t samples = 0;    // per point
    };
    // A point's estimate of one pass, before it joins the running mean.
    struct Shaded {
        std::size_t i;
        double value[3];
        double stream_variance, own_variance;  // luminance
    };
    auto shade_point = [&](PointLighting& shader, std::size_t i, const Pass& pass,
                           std::vector<Shaded>& out) {
        if (!covered(i) || state[i].done || cancel.load(std::memory_order_relaxed)) return;
        Shaded r{i, {}, 0, 0};
        double variance[3], own[3];
        try {
            if (settings.target == BakeTarget::Lightmap) {
                const TexelFootprint footprint(mesh, coverage, i, settings.smooth_normals);
                shader.shade(i, pass.first_round, pass.rounds, footprint.centre(), &footprint,
                             r.value, variance, pass.counts, own);
            } else {
                shader.shade(i, pass.first_round, pass.rounds, points[i], nullptr, r.value,
                             variance, pass.counts, own);
            }
        } catch (const LightingCancelled&) {
            return;  // context.keep_going: the bake is being cancelled
        }
        r.stream_variance = luminance(Vec3(variance[0], variance[1], variance[2]));
        r.own_variance = luminance(Vec3(own[0], own[1], own[2]));
        out.push_back(r);
        if (progress && (shaded.fetch_add(pass.samples, std::memory_order_relaxed) % 64) <
                            std::size_t(pass.samples))
            report_progress();
    };
    // A tile's points join their running means. Their variance: the
    // independent-draw formula (stable per point, but too high for correlated
    // draws) scaled by the tile's ratio of the streams' honest estimate to it
    // (many degrees of freedom once pooled over the tile), or the point's own
    // streams' estimate where that is larger.
    auto accumulate = [&](const Pass& pass, const std::vector<Shaded>& tile) {
        double sum_stream = 0, sum_own = 0;
        for (const Shaded& r : tile) {
            sum_stream += r.stream_variance;
            sum_own += r.own_variance;
        }
        const bool pooled = sum_own > 0;
        const double ratio = pooled ? sum_stream / sum_own : 1.0;
        for (const Shaded& r : tile) {
            PointState& s = state[r.i];
            ++s.passes;
            s.weight += pass.samples;
            const double weight = double(pass.samples) / s.weight;
            float* mean = &result.value[3 * r.i];
            for (int c = 0; c < 3; ++c)  // a mean past the float range stays infinite
                if (!std::isinf(mean[c])) mean[c] += float((r.value[c] - mean[c]) * weight);
            // The larger of the two: a tile's ratio comes mostly from its smooth
            // texels, and would understate a texel whose own streams disagree
            // more (rare bright samples, a shadow edge).
            const double variance =
                pooled ? std::max(r.own_variance * ratio, r.stream_variance) : r.stream_variance;
            s.variance_sum += double(pass.samples) * pass.samples * variance;
            // A point whose samples all agreed (nothing seen yet, typically a
            // shadowed texel that rare samples light) gives no error estimate:
            // it is not done, but keeps sampling while others still need to.
            if (settings.noise_target > 0 && s.passes >= kMinPassesForNoiseTarget &&
                s.variance_sum > 0 && relative_error(s, mean) <= settings.noise_target)
                s.done = true;
        }
    };
    auto run_pass = [&](const Pass& pass) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles, 1),
                          [&](const tbb::blocked_range<std::size_t>& range) {
            PointLighting& shader = shaders.local();
            std::vector<Shaded> shaded_tile;
            for (std::size_t tile = range.begin(); tile != range.end(); ++tile) {
                if (cancel.load(std::memory_order_relaxed)) return;
                shaded_tile.clear();
                tile_points(tile,
                            [&](std::size_t i) { shade_point(shader, i, pass, shaded_tile); });
                accumulate(pass, shaded_tile);
            }
        });
    };

    int pass_count = 0, done_rounds = 0;
    // Under a time budget the first pass — the part a budget cannot cut — is
    // a single round, so small budgets are not eaten by it.
    // (Optimal strategies solve per pass, and a one-round solve is poor:
    // they keep rounds_per_pass.)
    const bool single_first = settings.time_budget > 0 && !is_optimal(settings.lighting.strategy);
    int next_rounds = !progressive ? budget.full_rounds
                      : single_first ? 1
                                     : settings.rounds_per_pass;
    bool last_done = budget.last.empty();
    PassTimer timer;
    BakeStatus status = BakeStatus::Complete;
    for (;;) {
        Pass pass;
        pass.first_round = done_rounds;
        if (done_rounds < budget.full_rounds) {
            pass.rounds = std::min(next_rounds, budget.full_rounds - done_rounds);
        } else if (!last_done) {
            pass.rounds = 1;
            pass.counts = budget.last.data();
        } else {
            break;
        }
        if (settings.time_budget > 0 && pass_count > 0) {
            const double fits = timer.fit(settings.time_budget - elapsed());
            if (!pass.counts)
                pass.rounds = int(std::min<double>(pass.rounds, fits / budget.per_round));
            if (pass.rounds < 1 || (pass.counts && fits < budget.last_samples)) {
                status = BakeStatus::TimeBudget;
                break;
            }
        }
        pass.samples = pass.counts ? std::uint32_t(budget.last_samples)
                                   : std::uint32_t(pass.rounds * budget.per_round);
        const double pass_start = elapsed();
        run_pass(pass);
        timer.add(pass.samples, elapsed() - pass_start);
        ++pass_count;
        if (cancel) {
            status = BakeStatus::Cancelled;
            break;
        }
        if (pass.counts) last_done = true;
        done_rounds += pass.rounds;
        // Doubling keeps the per-pass cost small; under a noise target passes
        // grow by half only, so a texel overshoots its target by at most
        // √1.5 ≈ 1.22 in error.
        const double growth = settings.noise_target > 0 ? 1.5 : 2.0;
        next_rounds = int(std::min<double>(1 << 24, std::ceil(growth * pass.rounds)));
        if (settings.noise_target > 0 &&
            std::all_of(state.begin(), state.end(), [&](const PointState& s) {
                return s.done || (s.passes >= kMinPassesForNoiseTarget && s.variance_sum == 0);
            })) {
            status = BakeStatus::NoiseTarget;
            break;
        }
    }
    // Outputs, then the margin around UV islands.
    result.noise.assign(count, 0.f);
    result.mask.assign(count, 0.f);
    result.samples.assign(count, 0);
    for (std::size_t i = 0; i < count; ++i) result.samples[i] = state[i].weight;
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
        const std::vector<std::int64_t> source =
            settings.margin_type == MarginType::AdjacentFaces
                ? adjacent_margin_sources(coverage, mesh, settings.margin)
                : margin_sources(coverage, settings.margin);
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
    stats.passes = pass_count;
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
