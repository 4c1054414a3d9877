// The Baker: one bake of one mesh. Its rooms: bake.cpp (set-up, shading, the
// parallel passes), bake_schedule.{h,cpp} (PassSchedule), bake_means.{h,cpp}
// (RunningMeans), bake_allocation.{h,cpp} (SampleAllocation) and
// bake_outputs.cpp (the result and its statistics).
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
#include "bake/bake_schedule.h"
#include "bake/dyadic_schedule.h"
#include "render/direct_lighting.h"
#include "render/progress_throttle.h"
#include "scene/surface_contacts.h"

namespace omis::bake_detail {

// One bake of one mesh: the layout, the lighting, the points' running state
// (RunningMeans), the passes (PassSchedule, which says how they run) and
// what they leave in the result. Every pass reaches every point, and each
// point's draws continue one low-discrepancy sequence across passes.
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
    void run_passes();
    void record_pass(double sampling_start, bool tail);
    void forget_probe();
    void write_outputs();
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
    BakeResult result_;
    RunningMeans means_;
    PassSchedule schedule_;
    tbb::enumerable_thread_specific<PointLighting> shaders_;

    // Progress counts shaded samples; cancel is checked at every point so a
    // request stops the bake within one point's work.
    double total_work_ = 1;
    std::atomic<std::size_t> shaded_{0};
    std::atomic<bool> cancel_{false};
    ProgressThrottle report_throttle_;  // keep_going's progress reports
    std::mutex report_;

    std::uint64_t replaced_draws_ = 0;  // the probe's, when replaced

    // Sample allocation: on for this bake, and per tile.
    bool allocate_ = false;
    SampleAllocation allocation_;
};

}  // namespace omis::bake_detail
