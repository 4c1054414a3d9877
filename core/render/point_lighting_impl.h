// PointLighting's inner state and the functions its parts share (internal to
// the lighting core: render/*.cpp). The parts are defined by concern in
// point_lighting.cpp, point_setup.cpp, technique_draws.cpp, point_sample.cpp,
// integrand.cpp, light_tables.cpp, light_densities.cpp and point_estimate.cpp.
#pragma once

#include "render/direct_lighting.h"
#include "render/integrand.h"
#include "render/light_tables.h"
#include "render/point_estimate.h"
#include "render/lights_along.h"
#include "render/shape_draws.h"
#include "render/technique_draws.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "math/random.h"
#include "mis/allocation.h"
#include "mis/estimator.h"
#include "sampling/ellipse.h"
#include "sampling/sequence.h"
#include "sampling/spherical.h"
#include "sampling/warp.h"
#include "scene/ray_offset.h"

namespace omis {


// A triangle or rect smaller than this in solid angle (sr, estimated as area
// over the squared distance to its centroid) is sampled by area for
// `solid-angle`: the spherical polygon's setup would cost more than it saves,
// and the two densities nearly agree there. A function of (x, light) only, so
// pdf evaluation makes the same choice as sampling.
constexpr double kTinySolidAngle = 1e-3;
// `defensive` selection's uniform share where a world is among the lights
// (mix_in_uniform); half otherwise.
constexpr double kDefensiveShareWithWorld = 0.1;

// Where a light's size is compared (its centroid) and its area / kTinySolidAngle
// (infinite: never tiny), kept per light in the context: a compact record
// instead of a read of the whole Light among 100k (a cache miss each).
inline LightingContext::TinyShape tiny_shape_of(const Light& light) {
    LightingContext::TinyShape s;
    if (light.type == LightType::Triangle) {
        const TriangleLight& t = light.triangle;
        s.centroid = (t.p0 + t.p1 + t.p2) / 3.0;
        s.area_limit = light.triangle_area / kTinySolidAngle;
    }
    if (light.type == LightType::Rect) {
        const RectLight& r = light.rect;
        s.centroid = r.corner + (r.edge_u + r.edge_v) * 0.5;
        s.area_limit = r.area() / kTinySolidAngle;
    }
    return s;
}

inline bool tiny_in_solid_angle(const LightingContext::TinyShape& shape, const Vec3& x) {
    const Vec3 d = shape.centroid - x;
    return shape.area_limit < dot(d, d);
}

// Sorts `lights` and drops repeats. A closest hit's traversal lists a light
// or two (a closed mesh's near and far side): an insertion sort then, where
// std::sort's and std::unique's set-up were ~100 instructions a sample.
inline void sort_unique(std::vector<std::uint32_t>& lights) {
    constexpr std::size_t kFew = 8;
    if (lights.size() > kFew) {
        std::sort(lights.begin(), lights.end());
        lights.erase(std::unique(lights.begin(), lights.end()), lights.end());
        return;
    }
    for (std::size_t r = 1; r < lights.size(); ++r) {
        const std::uint32_t l = lights[r];
        std::size_t i = r;
        for (; i > 0 && lights[i - 1] > l; --i) lights[i] = lights[i - 1];
        lights[i] = l;
    }
    lights.erase(std::unique(lights.begin(), lights.end()), lights.end());
}

// Adds the seconds from its making to its end (or stop) to *into; with a
// null `into` it reads no clock (timing that is off costs nothing).
class ScopedTimer {
public:
    explicit ScopedTimer(double* into)
        : into_(into), start_(into ? Clock::now() : Clock::time_point()) {}
    ScopedTimer(const ScopedTimer&) = delete;
    ScopedTimer& operator=(const ScopedTimer&) = delete;
    ~ScopedTimer() { stop(); }
    void stop() {
        if (into_) *into_ += std::chrono::duration<double>(Clock::now() - start_).count();
        into_ = nullptr;
    }
    void discard() { into_ = nullptr; }  // the time so far counts nowhere

private:
    using Clock = std::chrono::steady_clock;
    double* into_;
    Clock::time_point start_;
};

// Past this many lights the context keeps no TinyShape table: the test then
// makes each light's record from its Light, which the sample reads anyway —
// among 100k lights the table's record is one more cache miss per light
// (emissive sphere 99224: 0.91-0.94x the time per sample), while a small
// table (128 KB at most) stays in cache and spares per-point tables' loops
// over every light the arithmetic (16 lights: 1.09x the time without it).
constexpr std::size_t kMaxTinyShapeTable = 4096;



struct PointLighting::Impl {
    Impl(const LightingContext& context, LightingCounters& counters)
        : p_(context), counters(counters), tables_(context), shapes_(context),
          lights_along_(context, shapes_, counters),
          integrand_(context, lights_along_, counters),
          draws_(context),
          estimate_(context, counters) {
        // Each table technique's probes' reach among a point's kept ones: a
        // byte per integrated light (LightingContext::keep_table_reach's layout).
        kept_reach_at_ = table_technique_offsets(context, context.integrated.size());
    }

    void shade(std::uint64_t point, int first_round, int rounds, const SurfacePoint& centre,
               const Footprint* footprint, const int* counts, double* value, double* variance,
               double* own_variance, StreamEstimates* streams,
               const std::vector<DrawnRounds>* earlier);

    // The per-sample loop's pieces (shade): which techniques take part, delta
    // lights at one position, one sample into its estimators.
    struct Active {
        std::vector<int> all, lights;  // technique indices
        std::uint64_t mask = 0, light_mask = 0;
        // The techniques of the hidden estimator's part (set_hidden_part):
        // the light techniques, or `bsdf` for a world seen through emitters.
        std::vector<int> hidden;
        std::uint64_t hidden_mask = 0;
        int draws_per_count = 1;  // settings.shadowed_draws where the probe says so
        void clear() {
            all.clear();
            lights.clear();
            hidden.clear();
            mask = light_mask = hidden_mask = 0;
            draws_per_count = 1;
        }
    };
    // shade's Active, kept from point to point: its vectors keep their
    // storage (two allocations per point were ~3 % of a one-round bake).
    Active active_scratch_;
    std::vector<int> scaled_counts_;  // shade's counts × draws_per_count
    int draws_per_count_ = 1;         // the last point shaded's (PointLighting::draws_per_count)
    void choose_active(std::uint64_t point, FootprintProbes& probes, const Footprint* footprint,
                       Active& active);
    // settings.shadowed_draws where centre_in_shadow, else 1; from the
    // context's shadow_verdicts where the job keeps them.
    int draws_per_count_at(std::uint64_t point, const SurfacePoint& centre);
    bool centre_in_shadow(const SurfacePoint& p);
    // centre_in_shadow's middle points, kept from point to point (no allocation).
    struct MiddlePoint {
        double weight;  // the light's unoccluded irradiance at p, by this one draw
        std::uint32_t light;
        Vec3 dir;
        double distance;
    };
    std::vector<MiddlePoint> middles_scratch_;
    // choose_active through the context's texel tables: with `keep`, a point
    // shaded before (same point id) takes its techniques and tables from there,
    // and one shaded first leaves them there for its next pass.
    void active_for(std::uint64_t point, bool keep, const SurfacePoint& centre,
                    const Footprint* footprint, Active& active);
    void restore(const TexelTables::Entry& kept, Active& active);
    using Estimators = EstimatorPair;
    bool in_hidden_part(int k) const {
        return p_.settings.techniques[k].bsdf == (integrand_.world_through() != ~0u);
    }
    void set_hidden_part(Active& active) const;
    // A world seen through emitters where light techniques reach the point:
    // the emitters' part is theirs alone (the main estimator holds only
    // them), the world's `bsdf`'s alone. Cosine draws estimate the
    // emitters worse than the solid-angle draws they would share them with
    // (emission_world reproduction, emitters alone, 64 samples: solid angle
    // alone relMSE 3.5e-5, with bsdf 1.4e-4), and a cosine draw then needs
    // one closest hit, no densities, no emitter query. Each part keeps a
    // technique that covers it: unbiased.
    bool split_parts(const Active& active) const {
        return integrand_.world_through() != ~0u && !pilot_ && !active.lights.empty() && !active.hidden.empty();
    }
    const std::vector<int>& main_techniques(const Active& active) const {
        return split_parts(active) ? active.lights : active.all;
    }
    void take_world_sample(const Active& active, const SurfacePoint& p, const Vec3& w, bool ok,
                           int hidden_index, const Estimators* into, int n_into);
    // take_world_sample around few occluders (EffectPlan::world_occluders): a
    // direction drawn toward their boxes (u_face picks a face, u1, u2 its
    // point) in place of the cosine direction w, which it falls back to
    // where the boxes do not bound what x may see.
    void take_occluder_sample(const Active& active, const SurfacePoint& p, double u_face,
                              double u1, double u2, const Vec3& w, bool ok, int hidden_index,
                              const Estimators* into, int n_into);
    // A selector technique's draw, made ahead of its sample (shade): its
    // footprint position, its light and the shape's pair (u1 the selection's
    // rest). Two samples ahead the tree is walked down to a cluster, whose
    // first line of the leaf-order CDF is then read (LightSelector::
    // begin_draw); one sample ahead the draw is finished there and the drawn
    // light's record is read. Each of these was a cache miss among thousands
    // of lights, and is now read while earlier samples trace their rays. The
    // same draw as at the sample: the tree's memo is a cache.
    struct SelectorDraw {
        int k = -1;  // -1: none made
        const ScrambledSobol* sequence = nullptr;
        std::uint32_t index = 0;
        const LightSelector* selector = nullptr;  // technique k's
        SurfacePoint p;
        double u1 = 0, u2 = 0;
        std::optional<SelectedLight> light;  // once finished
        bool finished = false;
        LightSelector::PartialDraw partial;  // until then
        bool is(int k_, const ScrambledSobol& sequence_, std::uint32_t index_) const {
            return k == k_ && sequence == &sequence_ && index == index_;
        }
    };
    void begin_selector_draw(int k, const ScrambledSobol& sequence, std::uint32_t index,
                             const SurfacePoint& centre, const Footprint* footprint,
                             SelectorDraw& d);
    void finish_selector_draw(SelectorDraw& d);
    void draw_selector(int k, const ScrambledSobol& sequence, std::uint32_t index,
                       const SurfacePoint& centre, const Footprint* footprint, SelectorDraw& d) {
        begin_selector_draw(k, sequence, index, centre, footprint, d);
        finish_selector_draw(d);
    }
    // shade's: the sample's, the next one's and the one's after
    static constexpr int kSelectorDraws = 3;
    SelectorDraw selector_draws_[kSelectorDraws];
    // `table_draw` for a technique that draws from a per-point table, `selected`
    // for one that draws from a selector (null for `bsdf`).
    struct SampleDraw;
    SampleDraw draw_direction(const Technique& t, int k, const SurfacePoint& p,
                              const ScrambledSobol& sequence, std::uint32_t index,
                              const TableDraw& table_draw, const SelectorDraw* selected);
    bool add_own_light_sample(const SampleDraw& d, const SurfacePoint& p, int hidden_index,
                              const Estimators* into, int n_into);
    void evaluate_and_add(const Active& active, std::size_t a, const SurfacePoint& p,
                          const SampleDraw& d, int hidden_index, const Estimators* into,
                          int n_into);
    void take_sample(const Active& active, std::size_t a, const ScrambledSobol& sequence,
                     std::uint32_t index, const SurfacePoint& centre, const Footprint* footprint,
                     const Estimators* into, int n_into, const TableDraw& table_draw,
                     const SelectorDraw* selected);
    void record_sample(const Active& active, std::size_t a, const double* pdfs, const Vec3& f,
                       std::uint64_t rays_before);
    AllocationPilot* pilot_ = nullptr;
    PointLighting::SetupTiming* setup_timing_ = nullptr;  // the owner's
    // Per table technique, the offset of its probes' reach among a point's
    // kept ones (LightingContext::table_reach); ~0 for the others.
    std::vector<std::size_t> kept_reach_at_;
    struct RoundLoop;
    void add_delta_round(int r, const SurfacePoint& centre, const Footprint* footprint,
                         DeltaSums& delta);

    // Starts reading the first two cache lines of light l's record, all that
    // an emissive triangle's sample reads (light.h).
    void prefetch_light(std::uint32_t l) const { prefetch_record(&p_.scene.lights()[l]); }
    // take_sample's shortcut for a light sample of integrand 0 (see there);
    // false: the sample still needs its densities.
    bool add_unlit_sample(std::size_t main_size, int main_index, int hidden_index,
                          double own_density, const Integrand::Value& f, const Estimators* into,
                          int n_into);
    double technique_pdf(int k, const Vec3& x, const Vec3& n, const Vec3& w);


    const LightingContext& p_;
    LightingCounters& counters;
    LightTables tables_;  // the point's, per light technique
    ShapeDraws shapes_;    // light shape draws and densities at the position
    LightsAlong lights_along_;  // the lights along the last direction asked about
    Integrand integrand_;       // the integrand along a direction, delta lights
    TechniqueDraws draws_;      // each technique's sequences and draw starts at the point
    PointEstimate estimate_;    // the point's estimators and its estimate
    // A table technique's density along a direction whose lights are not
    // listed yet: up to this many lights, a loop over the table's (a shape
    // test each, ~200 instructions) costs less than listing them (an Embree
    // query of the emitter shapes).
    static constexpr std::size_t kFewTableLights = 4;
    // technique_pdf's table slots along w, each with its light's index in
    // the lights along w (for its hit test, LightsAlong::tests_of).
    std::vector<std::pair<std::size_t, std::size_t>> along_slots_;
    // Whether a point with one light technique estimates each drawn light's
    // own part (take_sample). Not among emissive triangles: the triangles of
    // a closed mesh overlap along most directions (a sphere's far side behind
    // its near side), and a draw of an occluded far triangle would then add
    // nothing where the density of all of them along ω spreads the weight
    // (bench_emitters_quality, 32 spp: emissive_mesh 1.7×, sphere_near 2.9×
    // the variance). Among analytic lights: the same variance, at 0.65× the
    // CPU on 64 mixed lights and 0.88× on the demo room.
    const bool own_light_estimates_ = std::none_of(
        p_.scene.lights().begin(), p_.scene.lights().end(),
        [](const Light& l) { return l.type == LightType::Triangle; });
    // Whether shade draws each selector sample's light ahead of it
    // (SelectorDraw; set after p_). Among few lights (kMaxTinyShapeTable's
    // bound) their records stay in cache: the look-ahead's bookkeeping, ~140
    // instructions a sample, would buy nothing.
    const bool draw_next_ahead_ = p_.scene.lights().size() > kMaxTinyShapeTable;
    // p_.selector of each technique's selection (set after p_): a sample asks
    // twice (its draw, its density), and the context's switch cost ~35
    // instructions each time.
    const std::vector<const LightSelector*> technique_selectors_ = [this] {
        std::vector<const LightSelector*> s;
        for (const Technique& t : p_.settings.techniques) s.push_back(p_.selector(t.selection));
        return s;
    }();
    // Every light technique's table (if any) has weights that need no
    // irradiance (`uniform`, `power`: only which lights reach the probes):
    // active_for makes them again at every pass instead of keeping them in
    // the texel tables, which costs three allocations per texel, their
    // release at the end and a lookup per pass. Measured on the
    // emission_world reproduction (omis module, 128², one thread, CPU per
    // bake, best of 5 interleaved runs of 10): samples=2 42 → 34 ms;
    // samples=64 unchanged within the noise (±10 %).
    const bool cheap_tables_ = !p_.keeps_texel_tables;
    LightSelector::Memo memo_;  // the trees' branching at the current point
    // The light the sample being taken drew from `selector` at its position,
    // and the pmf the draw formed: its density takes that pmf, which the
    // memo does not hold for a light drawn ahead (SelectorDraw). The same
    // product pmf() would form.
    struct SampleSelection {
        const LightSelector* selector = nullptr;
        std::uint32_t light = ~0u;
        double pmf = 0;
    } sample_selection_;
    // The texel being shaded as a region (LightSelector::Receiver): a ball
    // about its centre through its footprint's corners (radius 0: none).
    // Selectors draw with the region's pmfs at every sample inside it — one
    // set per texel, kept in region_memo_ — instead of walking the tree
    // afresh at each sample's own position.
    LightSelector::Receiver region_;
    LightSelector::Memo region_memo_;
    // point: the shading's stream, whose radius the context may keep
    // (LightingContext::region_radii).
    void set_region(std::uint64_t point, FootprintProbes& probes);
    LightSelector::Receiver receiver_at(const Vec3& x, const Vec3& n,
                                        LightSelector::Memo*& memo);
};


}  // namespace omis
