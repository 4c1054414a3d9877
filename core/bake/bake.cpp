#include "bake/bake.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <stdexcept>

#include "bake/bake_points.h"
#include "bake/baker.h"
#include "bake/vertex_points.h"

namespace omis::bake_detail {
namespace {

constexpr std::size_t kSetupTimingStride = 7;  // odd: not aligned with power-of-two rows

BakeSettings with_receiver(const Scene& scene, BakeSettings settings) {
    settings.lighting.receiver = scene.mesh_receiver(settings.mesh);  // render/receiver.h
    settings.lighting.points_on_mesh = settings.mesh;  // texels and corners lie on it
    // A noise target stops on the error, so the error must be measured, not
    // bounded: independent streams (DirectLightingSettings::streams).
    if (settings.noise_target > 0) settings.lighting.streams = kMaxSampleStreams;
    return settings;
}

}  // namespace

Baker::Baker(const Scene& scene, const BakeSettings& settings, const BakeProgress& progress,
             Clock::time_point start)
    : scene_(scene),
      mesh_(scene.geometry().mesh(settings.mesh)),
      contacts_(scene.geometry(), settings.mesh),
      settings_(with_receiver(scene, settings)),
      progress_(progress),
      start_(start),
      layout_(mesh_, settings_),
      shape_(bake_shape(settings_, layout_)),
      context_(scene, settings_.lighting),
      budget_(plan_samples(context_, settings_.samples, settings_.lighting.rounds)),
      means_(layout_, settings_.lighting.streams > 1, settings_.noise_target, result_.value),
      schedule_(scene_, settings_, context_, budget_, layout_, result_, shape_, start_),
      shaders_([this] { return PointLighting(context_); }) {
    result_.width = layout_.width;
    result_.height = layout_.height;
    result_.value.assign(layout_.count * 3, 0.f);  // the running means
    // Only where some geometry can occlude the points.
    if (context_.plan.shadow_rays)
        buried_ = count_buried(scene_, layout_, mesh_, settings_.smooth_normals, contacts_);
    // Corners on another mesh's face: moved behind it (on_contact).
    for (std::size_t i = 0; i < layout_.points.size(); ++i)
        layout_.points[i] = on_contact(layout_.points[i], std::uint32_t(i / 3), &contacts_);
    // Progress counts the covered points' samples (the others are never shaded).
    std::size_t to_shade = 0;
    for (std::size_t i = 0; i < layout_.count; ++i) to_shade += layout_.covered(i);
    const long long samples_per_point =
        (long long)budget_.full_rounds * budget_.per_round + budget_.last_samples;
    total_work_ = double(std::max<std::size_t>(1, to_shade)) *
                  double(std::max<long long>(1, samples_per_point));
    context_.keep_going = [this] { return keep_going(); };
    // The points are 0 … count − 1; their slots (~48 bytes each, allocated,
    // zeroed and freed by every bake) only where the shading keeps tables: a
    // 128² samples=1 bake took 1.04–1.57× as long with them (budgets.txt).
    if (context_.keeps_texel_tables) context_.texel_tables.index_points(layout_.count);

    allocate_ = settings_.allocate_samples && is_optimal(settings_.lighting.strategy) &&
                context_.techniques.size() >= 2 && budget_.full_rounds >= 2;
    schedule_.start(allocate_);
    // Points shaded in more than one pass keep where their table draws stand
    // (LightingContext::draw_counts), which a later pass continues from,
    // whether their centre is in the shadow of most of their light
    // (shadow_verdicts), the reach behind their uniform or power tables
    // (table_reach), the radius of their footprint's region (region_radii) and
    // the light tree's branching there (region_branching).
    if (schedule_.progressive() || allocate_ || !budget_.last.empty()) {
        context_.keep_draw_counts(layout_.count);
        context_.keep_shadow_verdicts(layout_.count);
        context_.keep_table_reach(layout_.count);
        if (layout_.lightmap()) {
            context_.keep_region_radii(layout_.count);
            context_.keep_region_branching(layout_.count);
        }
    }
    if (allocate_) allocation_.start(layout_.tiles, budget_.per_round, context_.techniques.size());
}

void Baker::report_progress() {
    double fraction = double(shaded_.load(std::memory_order_relaxed)) / total_work_;
    if (settings_.time_budget > 0) fraction = std::max(fraction, elapsed() / settings_.time_budget);
    std::unique_lock<std::mutex> lock(report_, std::try_to_lock);
    if (lock.owns_lock() && !progress_(std::min(1.0, fraction))) cancel_ = true;
}

// Inside a point with huge counts: the cancel check, and progress now and
// then (ProgressThrottle; time budgets end on whole passes, never inside a point).
bool Baker::keep_going() {
    if (progress_ && report_throttle_.due(elapsed())) report_progress();
    return !cancel_.load(std::memory_order_relaxed);
}

void Baker::shade_point(PointLighting& shader, std::size_t i, const Pass& pass,
                        std::vector<Shaded>& out) {
    if (!layout_.covered(i) || means_.state(i).done || cancel_.load(std::memory_order_relaxed))
        return;
    Shaded r{i, {}, 0, {}, 1};
    double variance[3], own[3];
    StreamEstimates* streams = !means_.streams() ? nullptr : &r.streams;
    // The first pass times its set-up and sampling on every
    // kSetupTimingStride-th point only: clock reads at every point cost ~5 %
    // of a one-round pass (four then, six now), and time_pass needs only the
    // ratios of set-up and rounds to shading.
    shader.setup_timing.on = schedule_.passes() == 0 && i % kSetupTimingStride == 0;
    try {
        if (layout_.lightmap()) {
            const TexelFootprint footprint(mesh_, layout_.coverage, i, settings_.smooth_normals,
                                           &contacts_);
            shader.shade(i, pass.first_round, pass.rounds, footprint.centre(), &footprint, r.value,
                         variance, pass.counts, own, streams, pass.earlier);
        } else {
            shader.shade(i, pass.first_round, pass.rounds, layout_.points[i], nullptr, r.value,
                         variance, pass.counts, own, streams, pass.earlier);
        }
    } catch (const LightingCancelled&) {
        return;  // keep_going: the bake is being cancelled
    }
    r.own_variance = luminance(Vec3(own[0], own[1], own[2]));
    r.draws_per_count = shader.draws_per_count();
    out.push_back(r);
    if (progress_ && (shaded_.fetch_add(pass.samples, std::memory_order_relaxed) % 64) <
                         std::size_t(pass.samples))
        report_progress();
}

void Baker::run_pass(const Pass& pass) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(layout_.first_tile, layout_.end_tile, 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
        PointLighting& shader = shaders_.local();
        std::vector<Shaded> shaded_tile;
        for (std::size_t tile = range.begin(); tile != range.end(); ++tile) {
            if (cancel_.load(std::memory_order_relaxed)) return;
            shaded_tile.clear();
            means_.accumulate(shade_tile(shader, tile, pass, shaded_tile), shaded_tile);
        }
    });
}

void Baker::run_passes() {
    schedule_.size_first_pass();
    const double sampling_start = elapsed();
    for (;;) {
        Pass pass;
        if (!schedule_.plan_pass(pass)) return;
        if (schedule_.replace_probe()) forget_probe();
        const double pass_start = elapsed();
        run_pass(pass);
        schedule_.time_pass(pass.samples, elapsed() - pass_start, shaders_);
        schedule_.count_pass();
        if (cancel_) {
            schedule_.end(BakeStatus::Cancelled);
            return;
        }
        record_pass(sampling_start, pass.tail);
        schedule_.after_pass(pass);
        if (means_.noise_target_met()) {
            schedule_.end(BakeStatus::NoiseTarget);
            return;
        }
    }
}

// The probe pass's estimates leave the running means, the error tallies and
// the sample count (the next pass's estimates replace them).
void Baker::forget_probe() {
    schedule_.forget_probe();
    replaced_draws_ += means_.forget();
}

// The bake's convergence after a pass (convergence.h): what the running means
// have reached, and when.
void Baker::record_pass(double sampling_start, bool tail) {
    const double seconds = elapsed() - sampling_start;
    result_.stats.convergence.push_back(means_.record(seconds, tail));
}

BakeResult Baker::run() {
    run_passes();
    schedule_.remember_pass_cost();
    write_outputs();
    fill_margin();
    fill_stats();
    if (allocate_) allocation_.describe(result_.stats, settings_.lighting);
    return std::move(result_);
}

}  // namespace omis::bake_detail

namespace omis {

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
    const auto start = bake_detail::Clock::now();
    bake_detail::validate(scene, in);
    BakeSettings settings = in;
    if (settings.lighting.techniques.empty())
        default_techniques(scene, settings.lighting.techniques, settings.lighting.samples,
                           &settings.lighting.shadowed_draws);
    return bake_detail::Baker(scene, settings, progress, start).run();
}

}  // namespace omis
