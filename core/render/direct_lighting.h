// Direct lighting at shading points: E_direct/π per RGB channel (SPEC §3),
// every light technique combined with a MIS strategy, delta lights added
// outside MIS. Parallel over points; deterministic for a given seed at any
// thread count (each point draws from its own random stream).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
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

}  // namespace omis
