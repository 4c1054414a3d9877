// The Baker: one bake of one mesh. Its methods live in rooms of their own:
// bake.cpp (set-up, shading, the parallel passes), bake_schedule.cpp (the
// pass schedule), bake_means.cpp (running means), bake_allocation.cpp (sample
// allocation) and bake_outputs.cpp (the result and its statistics).
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <vector>

#include "bake/bake.h"
#include "bake/bake_allocation.h"
#include "bake/bake_layout.h"
#include "bake/bake_means.h"
#include "bake/dyadic_schedule.h"
#include "render/direct_lighting.h"
#include "render/progress_throttle.h"
#include "scene/surface_contacts.h"

namespace omis::bake_detail {

using Clock = std::chrono::steady_clock;

// One bake of one mesh: the layout, the lighting, the points' running state,
// the passes and what they leave in the result.
//
// Passes: all rounds at once unless a time or noise budget wants to look
// between passes. Under a noise target passes grow (rounds_per_pass, 1.5×
// that, ...), so the target is checked often early on and the per-pass cost
// (one solve per point) stays small later. Under a time budget alone: one
// round (measures the cost; or what an earlier bake's measure says fits:
// size_first_pass), then passes that end on powers of two of rounds and a
// tail block where the next net no longer fits (plan_dyadic_pass;
// bake/dyadic_schedule.h). Every pass reaches every point: a time budget
// ends on whole passes (the first always completes; the last takes the time
// the measured cost says is left), so all points end with the same count.
// Each point's draws continue one low-discrepancy sequence across passes.
class Baker {
public:
    Baker(const Scene& scene, const BakeSettings& settings, const BakeProgress& progress,
          Clock::time_point start);
    BakeResult run();

private:
    double elapsed() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
    void report_progress();
    bool keep_going();
    void shade_point(PointLighting& shader, std::size_t i, const Pass& pass,
                     std::vector<Shaded>& out);
    // The pass as the tile's points took it (an allocated tile's own rounds).
    Pass shade_tile(PointLighting& shader, std::size_t tile, const Pass& pass,
                    std::vector<Shaded>& out);
    void pilot_tile(PointLighting& shader, std::size_t tile, const Pass& pass,
                    std::vector<Shaded>& out);
    void run_pass(const Pass& pass);
    bool plan_pass(Pass& pass);
    bool plan_dyadic_pass(Pass& pass);
    void record_net_end();
    // Whether each pass fits its own α: an optimal strategy over two or more
    // techniques. With one technique its weights are balance's (the control
    // variate is constant), and so is its pass schedule.
    bool fits_per_pass() const {
        return is_optimal(settings_.lighting.strategy) && context_.techniques.size() >= 2;
    }
    void size_first_pass();
    void remember_pass_cost() const;
    void run_passes();
    void record_pass(double sampling_start, bool tail);
    void forget_probe();
    void time_pass(std::uint32_t samples, double seconds);
    void write_outputs();
    std::size_t count_buried() const;
    void fill_margin();
    void fill_stats();

    const Scene& scene_;
    const Mesh& mesh_;
    SurfaceContacts contacts_;  // where the mesh lies on others' faces (issue 32)
    std::size_t buried_ = 0;    // count_buried(), before any pass
    BakeSettings settings_;
    const BakeProgress& progress_;
    Clock::time_point start_;
    BakeLayout layout_;
    const std::uint64_t shape_;  // bake_shape: where the Scene keeps its pass cost
    LightingContext context_;
    SampleBudget budget_;
    bool progressive_;
    BakeResult result_;
    RunningMeans means_;
    tbb::enumerable_thread_specific<PointLighting> shaders_;

    // Progress counts shaded samples; cancel is checked at every point so a
    // request stops the bake within one point's work.
    double total_work_ = 1;
    std::atomic<std::size_t> shaded_{0};
    std::atomic<bool> cancel_{false};
    ProgressThrottle report_throttle_;  // keep_going's progress reports
    std::mutex report_;

    // The pass schedule.
    int pass_count_ = 0, done_rounds_ = 0, next_rounds_ = 0;
    int later_min_rounds_ = 1;  // the smallest pass after the first
    int last_pass_rounds_ = 1;  // of the pass that ran last
    bool probe_ = false;           // the first pass is a probe the next one replaces
    bool replace_probe_ = false;   // ... and it ran
    std::uint64_t replaced_draws_ = 0;  // the probe's, when replaced
    bool last_done_ = true;
    bool time_ends_ = false;  // the last pass took the time left
    PassTimer timer_;
    // The first pass's seconds beyond its rounds' sampling, as it measured
    // them (negative: not measured), for Scene::remember_pass_cost.
    double first_pass_fixed_ = -1;
    BakeStatus status_ = BakeStatus::Complete;
    // Time budgets without a noise target: passes end on powers of two
    // (dyadic_schedule.h); the running means' luminance at the last such end.
    bool dyadic_ = false;
    NetRate rate_;
    std::vector<float> net_end_luminance_;

    // Sample allocation: on for this bake, and per tile.
    bool allocate_ = false;
    SampleAllocation allocation_;
};

}  // namespace omis::bake_detail
