// The pass schedule of a bake: how many rounds each pass takes under a
// sample, time or noise budget, when the bake ends, and what its passes cost
// (kept in the Scene for the next bake of the same shape).
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
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <chrono>
#include <cstdint>
#include <vector>

#include "bake/bake.h"
#include "bake/bake_layout.h"
#include "bake/bake_means.h"
#include "bake/dyadic_schedule.h"
#include "render/direct_lighting.h"

namespace omis::bake_detail {

using Clock = std::chrono::steady_clock;

class PassSchedule {
public:
    PassSchedule(const Scene& scene, const BakeSettings& settings, const LightingContext& context,
                 const SampleBudget& budget, const BakeLayout& layout, const BakeResult& result,
                 std::uint64_t shape, Clock::time_point start);
    // The first pass; allocate: it is a sample allocation's pilot.
    void start(bool allocate);
    void size_first_pass();
    // The next pass, cut to what the time budget still fits; false: the bake ends.
    bool plan_pass(Pass& pass);
    // The pass that ran: its time, then its place in the schedule.
    void time_pass(std::uint32_t samples, double seconds,
                   tbb::enumerable_thread_specific<PointLighting>& shaders);
    void count_pass() { ++pass_count_; }
    void after_pass(const Pass& pass);
    // The probe's estimates are about to leave the running means.
    bool replace_probe() const { return replace_probe_; }
    void forget_probe();
    void end(BakeStatus status) { status_ = status; }
    void remember_pass_cost() const;

    bool progressive() const { return progressive_; }
    int passes() const { return pass_count_; }
    BakeStatus status() const { return status_; }

private:
    double elapsed() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
    bool plan_dyadic_pass(Pass& pass);
    void record_net_end();
    // Whether each pass fits its own α: an optimal strategy over two or more
    // techniques. With one technique its weights are balance's (the control
    // variate is constant), and so is its pass schedule.
    bool fits_per_pass() const {
        return is_optimal(settings_.lighting.strategy) && context_.techniques.size() >= 2;
    }

    const Scene& scene_;
    const BakeSettings& settings_;
    const LightingContext& context_;
    const SampleBudget& budget_;
    const BakeLayout& layout_;
    const BakeResult& result_;  // its values: the running means
    const std::uint64_t shape_;  // bake_shape: where the Scene keeps its pass cost
    const Clock::time_point start_;
    const bool progressive_;  // passes look between them (a time or noise budget)

    int pass_count_ = 0, done_rounds_ = 0, next_rounds_ = 0;
    int later_min_rounds_ = 1;  // the smallest pass after the first
    int last_pass_rounds_ = 1;  // of the pass that ran last
    bool probe_ = false;           // the first pass is a probe the next one replaces
    bool replace_probe_ = false;   // ... and it ran
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
};

}  // namespace omis::bake_detail
