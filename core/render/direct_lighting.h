// Direct lighting at shading points: E_direct/π per RGB channel (SPEC §3),
// every light technique combined with a MIS strategy, delta lights added
// outside MIS. Parallel over points; deterministic for a given seed at any
// thread count (each point draws from its own random stream).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "mis/strategy.h"
#include "render/effect_plan.h"
#include "render/receiver.h"
#include "render/light_selection.h"
#include "render/scene.h"
#include "render/texel_draws.h"
#include "render/texel_tables.h"

namespace omis {

class AllocationPilot;

struct DirectLightingSettings {
    std::vector<Technique> techniques;
    std::vector<int> samples;  // per technique, per round
    int rounds = 1;
    Strategy strategy = Strategy::OptimalDirect;
    StrategyOptions options;
    std::uint64_t seed = 0;
    // Independently randomized streams a point's rounds are dealt to (round r
    // to stream r mod streams; 1..kMaxSampleStreams). 1: one scrambled
    // sequence per technique, the least error per sample; the variance it
    // reports is the independent-draw formula, an over-estimate for these
    // stratified draws (2–30× on smooth lighting, tests/core/test_bake.cpp).
    // More: the spread of the streams' estimates measures the actual error —
    // what a noise target stops on — at the cost of the stratification
    // across streams (2–3× the error per sample with 4 on the Cycles race).
    int streams = 1;
    // Shortcuts that give the same estimates with less work (a light
    // sample's emitter query stopped at its closest hit; no densities for a
    // sample of integrand 0 where the estimator does not use them). false:
    // the general path, which tests compare them with.
    bool fast_paths = true;
    // Points whose centre does not see the middle points of the integrated
    // lights that bring at least kShadowedShare of the light there unoccluded
    // (a deterministic probe, kept per texel: the point's draw counts are
    // fixed before its samples, so estimates stay unbiased) draw this many
    // times each technique's count a round. 1: no probe.
    int shadowed_draws = 1;
    // The receiving surface's diffuse closure at every point (render/receiver.h);
    // bake() takes it from the scene's mesh.
    Receiver receiver;
    // The mesh every point shaded lies on (bake() sets its mesh); ~0u: points
    // anywhere. The effect plan traces no shadow rays where it is flat and
    // every mesh lies in its plane (EffectPlan::shadow_rays).
    std::uint32_t points_on_mesh = ~0u;
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
// that receives light). value, variance: count × 3 doubles written (variance may
// be null).
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
    // Hands its kept branching's block on to the next context (keep_region_branching).
    ~LightingContext();
    LightingContext(const LightingContext&) = delete;
    LightingContext& operator=(const LightingContext&) = delete;

    const Scene& scene;
    const DirectLightingSettings settings;
    const EffectPlan plan;
    std::vector<int> techniques;  // enabled technique indices
    std::vector<std::uint32_t> integrated, delta;
    const std::vector<double>& power;  // per light, for `power` selection (the scene's)
    // Per light, what tells whether a rect or triangle is tiny in solid angle
    // at x (then sampled by area for `solid-angle`; shape_draws.h);
    // empty among many lights, where each light's is made from the light.
    struct TinyShape {
        Vec3 centroid;
        double area_limit = std::numeric_limits<double>::infinity();
    };
    std::vector<TinyShape> tiny_shapes;
    // Selection of integrated lights for `uniform`, `power` and `tree`
    // (built when a technique uses it), and of delta lights when the plan
    // estimates their sum by drawing some (plan.sample_delta_lights). The
    // scene's own, built once per scene (a tree over 16k emissive triangles is
    // megabytes: not copied per bake); null where no technique uses one.
    const LightSelector* uniform_selector = nullptr;
    const LightSelector* power_selector = nullptr;
    const LightSelector* tree_selector = nullptr;
    const LightSelector* delta_selector = nullptr;
    const LightSelector* selector(SelectionRule selection) const;
    // Per texel (PointLighting::shade's point id), what a bake's later passes
    // reuse: the techniques taking part and their light tables.
    mutable TexelTables texel_tables;
    // Whether shading keeps anything there: not when every light technique's
    // table needs no irradiance (`uniform`, `power`: cheaper to make again
    // at every pass than to keep; point_setup.cpp). A bake then need not
    // index its points in texel_tables.
    bool keeps_texel_tables = true;
    // Per point (PointLighting::shade's point id), where its table draws stand
    // (render/texel_draws.h), so that a later call continues from there:
    // kept by a job that shades points 0 … points − 1 in several passes
    // (keep_draw_counts). 4 bytes per point, light technique that draws from
    // a per-point table, stream and integrated light; none past
    // TexelDrawCounts::kByteBudget.
    mutable TexelDrawCounts draw_counts;
    void keep_draw_counts(std::size_t points);
    // Per point, where no texel tables are kept (keeps_texel_tables false:
    // every table weighs by no irradiance), which of its footprint's probes
    // each light reaches, per table technique (render/texel_draws.h): a later
    // pass makes the same tables from them instead of probing again (~37 %
    // of what a later pass repeated on the race's area scene). 1 byte per
    // point, table technique and integrated light; none past the budget.
    mutable TexelReach table_reach;
    void keep_table_reach(std::size_t points);
    // Per point, where settings.shadowed_draws > 1: its draws per count (1, or
    // shadowed_draws where its centre is shadowed: centre_in_shadow), 0 before its
    // first call. The probe behind it is deterministic, so a job of several
    // passes keeps the verdict (keep_shadow_verdicts) and traces the probe's
    // rays once per point instead of once per pass where texel tables are not
    // kept. 1 byte per point.
    mutable std::vector<std::uint8_t> shadow_verdicts;
    void keep_shadow_verdicts(std::size_t points);
    // Per point with a footprint, where a technique draws from a selector:
    // the radius of the region its samples draw lights for (the footprint's
    // farthest corner from its centre), negative before its first call. A
    // job of several passes keeps it (keep_region_radii) instead of placing
    // the four corners again at every pass (~900 instructions a texel and
    // pass on the race's emissive_mesh, a fifth of what a later pass
    // repeats there). 8 bytes per point.
    mutable std::vector<double> region_radii;
    void keep_region_radii(std::size_t points);
    // Per point with a footprint, where a technique draws from the tree: the
    // branching its region's memo computed (LightSelector::Memo::keep_in),
    // region_nodes wide nodes each, the first walked. A job of several passes
    // keeps it (keep_region_branching) instead of evaluating the same nodes'
    // bounds again at every pass (a third of what a later pass repeated on
    // the race's emissive_mesh). 20 bytes a node, up to max_nodes a point
    // (16: the nodes a texel's first rounds walk; more saved little), fewer
    // past kRegionBranchingBytes in all, none past it with one. The bound is
    // small because a bake's new pages cost their first touch: Blender's
    // allocator (jemalloc) hands a block below 8 MiB to the next bake as it
    // is, a larger one anew (bench/results/emitters.txt) — and even a smaller
    // one anew at times, so contexts hand the block on themselves (one spare
    // per process, at most this size).
    static constexpr std::size_t kRegionBranchingBytes = std::size_t(6) << 20;
    static constexpr std::size_t kMaxRegionNodes = 16;
    mutable std::vector<LightSelector::KeptNode> region_branching;
    std::size_t region_nodes = 0;
    void keep_region_branching(std::size_t points, std::size_t max_nodes = kMaxRegionNodes);
    // The point's kept nodes, null where none are kept.
    LightSelector::KeptNode* region_branching_of(std::uint64_t point) const {
        return region_nodes > 0 && point < region_branching.size() / region_nodes
                   ? &region_branching[point * region_nodes]
                   : nullptr;
    }

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

// A shading point: position, shading normal, geometric normal (places ray
// origins).
struct SurfacePoint {
    Vec3 x, n, ng;
};

// A region of surface a point's samples spread over (a texel's footprint):
// maps a 2-D draw in [0,1)² to a surface point, uniformly in the region's
// own parameter space (UV for texels), as the receiver's box filter.
class Footprint {
public:
    virtual ~Footprint() = default;
    virtual SurfacePoint at(double u, double v) const = 0;

    // Where the `unoccluded` weights of a light table (a light's unoccluded
    // irradiance, costly for spread and round lights) may be measured instead
    // of at the footprint's centre: a point near it that neighbouring
    // footprints share (a bake's block of texels on one triangle), named by
    // `id`, so they share one measurement. Any positive weight keeps the
    // combination unbiased; a light that does not reach the anchor is weighed
    // at the centre as before. false: no anchor (every weight at the centre).
    struct Anchor {
        std::uint64_t id = 0;
        SurfacePoint at;
    };
    virtual bool table_anchor(Anchor&) const { return false; }
};

// The most independently randomized streams a point's rounds may be dealt to
// (DirectLightingSettings::streams); 4 give the error estimate three degrees
// of freedom per point before pooling.
constexpr int kMaxSampleStreams = 4;

// A point's estimate per randomization stream (luminance) and the rounds
// behind each, for callers that combine a point's passes and measure the
// error of the combination from the streams' spread (the baker).
struct StreamEstimates {
    int rounds[kMaxSampleStreams] = {};
    double luminance[kMaxSampleStreams] = {};
};

// Rounds a point drew earlier with other counts than the settings' (sample
// allocation between passes, issue 10): a later call continues every
// technique's sequences after the draws these took.
struct DrawnRounds {
    int first_round = 0, rounds = 0;
    const int* counts = nullptr;  // per technique and round; null: the settings'
};

// Shades one point at a time; one per thread, as it keeps scratch memory.
class PointLighting {
public:
    explicit PointLighting(const LightingContext& context);
    ~PointLighting();
    PointLighting(PointLighting&&) noexcept;
    PointLighting(const PointLighting&) = delete;

    // E/π and the estimated variance of that estimate (RGB) at a point, from
    // rounds [first_round, first_round + rounds) of its draws. Every sample's
    // dimensions (footprint position, light selection, light shape or BSDF
    // direction) come from one Owen-scrambled Sobol' sequence per technique
    // and randomization stream (settings.streams), fixed by (seed, stream):
    // unbiased, stratified, and continued — not restarted — by a later
    // first_round. The variance comes from the spread between the streams'
    // estimates when at least two hold rounds, else from the estimator's own
    // (independent-draw) formula.
    // point names the point within the context: with a footprint, or from
    // its second call on (first_round > 0), the point's techniques and light
    // tables are kept under it (LightingContext::texel_tables) and reused, so
    // one point id must always mean the same point and footprint.
    // footprint: null = every sample at `centre`; else each sample draws its
    // own position from it (delta lights then take one position per round).
    // counts: samples per technique in each of these rounds (null = the
    // settings' counts); another count vector is meant for a final partial
    // pass (an exact sample budget). own_variance, if given, receives the
    // variance as computed for independent draws (many degrees of freedom,
    // but too high for correlated draws): callers may pool the ratio of the
    // two over neighbouring points. variance may be null (then the streams
    // are not compared, which saves their estimators). streams, if given,
    // receives each stream's estimate of these rounds.
    // earlier: every call before this one for the same point, in order, when
    // their counts were not all the settings' (their rounds must add up to
    // first_round; std::invalid_argument otherwise).
    void shade(std::uint64_t point, int first_round, int rounds, const SurfacePoint& centre,
               const Footprint* footprint, double value[3], double variance[3],
               const int* counts = nullptr, double own_variance[3] = nullptr,
               StreamEstimates* streams = nullptr,
               const std::vector<DrawnRounds>* earlier = nullptr);
    // A fixed point x with shading normal n and geometric normal ng.
    void shade(std::uint64_t point, int first_round, int rounds, const Vec3& x, const Vec3& n,
               const Vec3& ng, double value[3], double variance[3]);

    // While set, every sample of the points shaded goes to `pilot` too (its
    // techniques are the settings', its integrand the luminance of f) with
    // its work (1 + the rays it traced); the caller ends each point
    // (AllocationPilot::end_point). Null stops recording.
    void record_into(AllocationPilot* pilot);

    LightingCounters counters;
    // The last point shaded drew this many times each count a round:
    // settings.shadowed_draws where its centre does not see the middle points
    // of the lights that bring most of its light, else 1 (a bake reports
    // those texels and their extra draws).
    int draws_per_count() const;

    // What a bake's first pass spends that its later passes do not: the
    // set-up of the tables kept for a point's later passes, beside all of the
    // shading, in seconds, timed while `on`. The bake predicts a later pass's
    // duration from the first one without that set-up. `rounds`: the part
    // spent drawing the rounds' samples, which grows with the rounds (the
    // rest of a point's shading every pass repeats whatever its size).
    struct SetupTiming {
        bool on = false;
        double kept_setup = 0, shading = 0, rounds = 0;
    };
    SetupTiming setup_timing;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace omis
