// Direct lighting at shading points: E_direct/π per RGB channel (SPEC §3),
// every light technique combined with a MIS strategy, delta lights added
// outside MIS. Parallel over points; deterministic for a given seed at any
// thread count (each point draws from its own random stream).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "mis/strategy.h"
#include "render/effect_plan.h"
#include "render/scene.h"

namespace omis {

struct DirectLightingSettings {
    std::vector<Technique> techniques;
    std::vector<int> samples;  // per technique, per round
    int rounds = 1;
    Strategy strategy = Strategy::OptimalDirect;
    StrategyOptions options;
    std::uint64_t seed = 0;
};

struct DirectLightingStats {
    std::uint64_t points = 0;
    std::uint64_t samples = 0;           // directions drawn
    std::uint64_t rays_traced = 0;       // shadow and BSDF rays handed to Embree
    std::uint64_t mis_systems = 0;       // per-point estimators built
    std::uint64_t pdf_evaluations = 0;   // light-technique pdf evaluations
    double seconds = 0;
    bool cancelled = false;
    EffectPlan plan;
};

// Called now and then with the fraction done, from any thread; returning
// false cancels (the stats say so, outputs are then incomplete).
using ProgressFunction = std::function<bool(double)>;

// points, normals: count × 3 doubles (normals unit length, facing the side
// that receives light). value, variance: count × 3 doubles written.
DirectLightingStats direct_lighting(const Scene& scene, const double* points,
                                    const double* normals, std::size_t count,
                                    const DirectLightingSettings& settings, double* value,
                                    double* variance,
                                    const ProgressFunction& progress = nullptr);

// The building blocks of direct_lighting, for callers that choose their own
// points and passes (the baker).

// What a lighting job prepares once: validated settings, the effect plan, the
// lights by role and their powers.
class LightingContext {
public:
    // Throws std::invalid_argument / std::logic_error on bad settings or an
    // uncommitted scene.
    LightingContext(const Scene& scene, const DirectLightingSettings& settings);

    const Scene& scene;
    const DirectLightingSettings settings;
    const EffectPlan plan;
    std::vector<int> techniques;  // enabled technique indices
    std::vector<std::uint32_t> integrated, delta;
    std::vector<double> power;  // per light, for `power` selection

    // Polled every few hundred samples inside PointLighting::shade, so a
    // point with huge counts can still be stopped: returning false makes
    // shade throw LightingCancelled. Empty: never polled.
    std::function<bool()> keep_going;
};

// Thrown by PointLighting::shade when the context's keep_going says stop; the
// point's outputs are then not written.
struct LightingCancelled {};

struct LightingCounters {
    std::uint64_t samples = 0, rays = 0, systems = 0, pdf_evaluations = 0;
};

// Shades one point at a time; one per thread, as it keeps scratch memory.
class PointLighting {
public:
    explicit PointLighting(const LightingContext& context);
    ~PointLighting();
    PointLighting(PointLighting&&) noexcept;
    PointLighting(const PointLighting&) = delete;

    // E/π and its estimated variance (RGB) at x with shading normal n, from
    // rounds [first_round, first_round + rounds) of this point's draws. Each
    // technique's draws at a point are one randomly shifted low-discrepancy
    // (R3) sequence, fixed by (seed, stream): unbiased, far less noisy than
    // independent draws, and continued — not restarted — when a point is
    // shaded again with a later first_round. The variance is estimated as for
    // independent draws, so it is an upper bound. ng, the geometric normal,
    // places the ray origins.
    void shade(std::uint64_t stream, int first_round, int rounds, const Vec3& x, const Vec3& n,
               const Vec3& ng, double value[3], double variance[3]);

    LightingCounters counters;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace omis
