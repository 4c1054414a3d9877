// direct_lighting(): shading points in parallel, with progress and
// cancellation (the lighting core's rooms: README, Architecture).
#include "render/direct_lighting.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>

#include "render/progress_throttle.h"
#include "scene/ray_offset.h"

namespace omis {

DirectLightingStats direct_lighting(const Scene& scene, const double* points,
                                    const double* normals, std::size_t count,
                                    const DirectLightingSettings& settings, double* value,
                                    double* variance, const ProgressFunction& progress) {
    const auto start = std::chrono::steady_clock::now();
    LightingContext context(scene, settings);
    for (std::size_t i = 0; i < 3 * count; ++i)  // Embree's range (issue 11)
        if (!(std::abs(points[i]) <= kLargestTraceableCoordinate))
            throw std::invalid_argument("points: point " + std::to_string(i / 3) +
                                        " has a coordinate beyond ±1e18 m (or not finite)");

    DirectLightingStats stats;
    stats.plan = context.plan;
    tbb::enumerable_thread_specific<PointLighting> shaders(
        [&] { return PointLighting(context); });
    std::atomic<bool> cancel{false};
    std::atomic<std::size_t> done{0};
    std::mutex report;
    // Inside long points: report progress now and then (ProgressThrottle)
    // and stop once it asks to.
    ProgressThrottle throttle;
    auto seconds = [&] {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    context.keep_going = [&] {
        if (progress && throttle.due(seconds())) {
            std::unique_lock<std::mutex> lock(report, std::try_to_lock);
            if (lock.owns_lock() && !progress(double(done.load()) / double(count))) cancel = true;
        }
        return !cancel.load(std::memory_order_relaxed);
    };

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
        if (cancel.load(std::memory_order_relaxed)) return;
        PointLighting& shader = shaders.local();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const Vec3 x(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
            const Vec3 n(normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]);
            // One stream: the variance as for independent draws, an upper
            // estimate for these stratified ones. Several: the streams'
            // spread (three degrees of freedom with four: noisy per point).
            // variance may be null: the caller wants values only.
            double* out = variance ? variance + 3 * i : nullptr;
            const bool spread = settings.streams > 1;
            try {
                shader.shade(i, 0, settings.rounds, SurfacePoint{x, n, n}, nullptr,
                             value + 3 * i, spread ? out : nullptr, nullptr,
                             spread ? nullptr : out);
            } catch (const LightingCancelled&) {
                return;
            }
        }
        const std::size_t finished = done.fetch_add(range.size()) + range.size();
        if (progress) {
            std::unique_lock<std::mutex> lock(report, std::try_to_lock);
            if (lock.owns_lock() && !progress(double(finished) / double(count)))
                cancel = true;
        }
    });

    for (const PointLighting& s : shaders) {
        stats.samples += s.counters.samples;
        stats.rays_traced += s.counters.rays;
        stats.mis_systems += s.counters.systems;
        stats.pdf_evaluations += s.counters.pdf_evaluations;
    }
    stats.points = done.load();
    stats.cancelled = cancel.load();
    stats.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return stats;
}

}  // namespace omis
