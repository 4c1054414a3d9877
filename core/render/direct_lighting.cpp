#include "render/direct_lighting.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

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
namespace {

// An emissive triangle is geometry too: a closest hit within this relative
// depth of it is the emitter itself or a coplanar neighbour, not a blocker.
constexpr double kEmitterDepthTolerance = 1e-4;

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
LightingContext::TinyShape tiny_shape_of(const Light& light) {
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

bool tiny_in_solid_angle(const LightingContext::TinyShape& shape, const Vec3& x) {
    const Vec3 d = shape.centroid - x;
    return shape.area_limit < dot(d, d);
}

// Sorts `lights` and drops repeats. A closest hit's traversal lists a light
// or two (a closed mesh's near and far side): an insertion sort then, where
// std::sort's and std::unique's set-up were ~100 instructions a sample.
void sort_unique(std::vector<std::uint32_t>& lights) {
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

// A light technique at one point (`unoccluded`, exact per light): the lights
// it may pick and their CDF.
struct LightChoice {
    std::vector<std::uint32_t> lights;
    std::vector<double> probability, cdf;
};

}  // namespace

struct PointLighting::Impl {
    Impl(const LightingContext& context, LightingCounters& counters)
        : p_(context), counters(counters), choices_(context.settings.techniques.size()) {
        // Where each table technique's counts lie among a point's kept ones
        // (LightingContext::keep_draw_counts' layout).
        // Likewise their probes' reach (LightingContext::keep_table_reach's).
        std::size_t cells = 0, reach_cells = 0;
        for (const Technique& t : p_.settings.techniques) {
            const bool table = !t.bsdf && !p_.selector(t.selection);
            kept_counts_at_.push_back(table ? cells : ~std::size_t(0));
            kept_reach_at_.push_back(table ? reach_cells : ~std::size_t(0));
            if (table) cells += std::size_t(p_.settings.streams) * p_.integrated.size();
            if (table) reach_cells += p_.integrated.size();
        }
    }

    void shade(std::uint64_t stream, int first_round, int rounds, const SurfacePoint& centre,
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
    class Probes;
    void choose_active(std::uint64_t point, Probes& probes, const Footprint* footprint,
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
    // shaded before (same stream) takes its techniques and tables from there,
    // and one shaded first leaves them there for its next pass.
    void active_for(std::uint64_t stream, bool keep, const SurfacePoint& centre,
                    const Footprint* footprint, Active& active);
    void restore(const TexelTables::Entry& kept, Active& active);
    Vec3 delta_lighting(const SurfacePoint& p, double u);
    struct Estimators {
        MisEstimator* main;
        // A part of the integrand only some techniques estimate (null if none):
        // lights invisible to BSDF rays (the light techniques'), or the world
        // seen through emitters (world_through_, `bsdf`'s).
        MisEstimator* hidden;
    };
    bool in_hidden_part(int k) const {
        return p_.settings.techniques[k].bsdf == (world_through_ != ~0u);
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
        return world_through_ != ~0u && !pilot_ && !active.lights.empty() && !active.hidden.empty();
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
    // A light drawn from a per-point table before the sample (LightStreams):
    // its slot in the table, its shape point and its footprint position.
    struct TableDraw {
        int slot = -1;  // -1: take_sample selects (bsdf, selectors)
        double u1 = 0, u2 = 0;
        double fu = 0, fv = 0;
    };
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
    // `drawn` for a technique that draws from a per-point table, `selected`
    // for one that draws from a selector (null for `bsdf`).
    void take_sample(const Active& active, std::size_t a, const ScrambledSobol& sequence,
                     std::uint32_t index, const SurfacePoint& centre, const Footprint* footprint,
                     const Estimators* into, int n_into, const TableDraw& drawn,
                     const SelectorDraw* selected);
    // Sample allocation (issue 10): where each technique's draws of a call
    // start in each stream's sequence — after those of the earlier calls,
    // whose counts may differ from the settings' — and the pilot recording.
    void set_draw_starts(int first_round, const std::vector<DrawnRounds>* earlier);
    std::uint32_t draw_start(int k, int s) const {
        return draw_start_[std::size_t(k) * std::size_t(p_.settings.streams) + std::size_t(s)];
    }
    // Rounds of stream s (of K) among rounds [0, end_round).
    static int rounds_in_stream(int s, int end_round, int K) {
        return end_round > s ? (end_round - s + K - 1) / K : 0;
    }
    void record_sample(const Active& active, std::size_t a, const double* pdfs, const Vec3& f,
                       std::uint64_t rays_before);
    std::vector<std::uint32_t> draw_start_;
    AllocationPilot* pilot_ = nullptr;
    PointLighting::SetupTiming* setup_timing_ = nullptr;  // the owner's
    class LightStreams;
    // LightStreams' storage, kept from point to point (no allocation per
    // point and pass): per technique, stream and table slot, the draws taken
    // and the slot's own sequence once made.
    std::vector<std::uint32_t> taken_scratch_;
    std::vector<std::optional<ScrambledSobol>> sequences_scratch_;
    // Per table technique, the offset of its counts among a point's kept
    // ones (LightingContext::draw_counts); ~0 for the others.
    std::vector<std::size_t> kept_counts_at_;
    std::vector<std::size_t> kept_reach_at_;  // ... of its reach (LightingContext::table_reach)
    // Each (technique, stream) sequence of the point being shaded, and the
    // delta lights' per stream (technique index techniques.size()): made at
    // its first use in a call, not at every round or by every user — its
    // seed hashes were ~190 of a sample's ~5,150 instructions on an
    // emission_world-like bake (callgrind). Same seeds: bit-identical results.
    std::vector<std::optional<ScrambledSobol>> technique_sequences_;
    std::uint64_t sequence_base_ = 0;  // the point's (shade)
    // `count` sequences, none made yet: clears only their flags (assigning
    // nullopt copied whole ~100-byte objects, ~5 % of a later pass's
    // repeated work).
    static void forget_sequences(std::vector<std::optional<ScrambledSobol>>& sequences,
                                 std::size_t count) {
        sequences.resize(count);
        for (std::optional<ScrambledSobol>& s : sequences) s.reset();
    }
    const ScrambledSobol& technique_sequence(std::size_t k, int s) {
        const std::size_t K = std::size_t(p_.settings.streams);
        std::optional<ScrambledSobol>& built = technique_sequences_[k * K + std::size_t(s)];
        if (!built) built.emplace(sequence_base_ ^ mix64(std::uint64_t(k) * K + std::uint64_t(s) + 1));
        return *built;
    }
    // shade's pieces: how its rounds fall into the streams, the estimators
    // they go to, the delta lights' sums, and the point's estimate from them.
    struct RoundPlan {
        int rounds = 0;
        int stream_rounds[kMaxSampleStreams] = {};
        int streams_used = 0;
        bool by_stream = false;  // each stream's estimate is kept
        bool in_whole = false;   // ... as sums inside the whole's estimators
    };
    RoundPlan plan_rounds(int first_round, int rounds, bool want_error) const;
    void set_up_estimators(const Active& active, const RoundPlan& plan, const int* counts,
                           bool fresh, Estimators& all, Estimators* per);
    struct DeltaSums {
        bool per_round = false;  // a position per round (else at_centre)
        Vec3 sum[kMaxSampleStreams], sum2, at_centre;
    };
    Vec3 point_estimate(const Active& active, const RoundPlan& plan, const Estimators& all,
                        const Estimators* per, const DeltaSums& delta, Vec3& own_variance,
                        Vec3& error_variance, StreamEstimates* streams);
    // Sum of the estimates (and their own variance estimates, if asked).
    // The estimators' results stay in results_ (main, hidden) until the next call.
    Vec3 estimate_of(const Estimators& e, Vec3* variance = nullptr);
    // Stream s's estimate from the whole's per-stream sums (streams_in_whole):
    // its balance (heuristics: own) estimate, and (cross_fit, optimal-direct)
    // that corrected with the α of the other streams (MisEstimator::stream_cross_fit).
    void stream_of(const Estimators& whole, int s, bool cross_fit, Vec3& balance,
                   Vec3& corrected) const;
    // The balance heuristic's estimate from the same samples (optimal
    // strategies accumulate it alongside their moments).
    static Vec3 balance_of(const Estimators& e);
    // Whether the whole's estimators keep the per-stream sums (MisEstimator::
    // set_streams) instead of an estimator per stream: every strategy but
    // optimal-progressive, whose stream estimates need their own cross-fit.
    static bool streams_in_whole(Strategy strategy, bool by_stream) {
        return by_stream && strategy != Strategy::OptimalProgressive;
    }
    static void set_streams(const Estimators& all, int count);
    static void set_stream(const Estimators& all, int s);
    MisResult results_[2];  // estimate_of's (main, hidden), reused from point to point
    // Optimal strategies: whether the independent streams say the optimal
    // estimate is noisier here than the balance heuristic's.
    static bool balance_is_better(const Vec3* optimal, const Vec3* balance,
                                  const int* stream_rounds);

    struct Integrand {
        // Lights BSDF rays see, and those they do not (or, world_through_: the
        // emitters' part and the world's, seen through emitters).
        Vec3 main, hidden;
    };
    // world_through_: moves the world's part of f (a direction whose first
    // hit, `blocker`, if any, emits) from main to hidden, where main holds it
    // already (nothing hit) or holds the emitter's L_e (L_e − L_w). Without
    // such a world the blocker's mesh is not looked up (~30 instructions a
    // sample among emissive triangles).
    void split_world(Integrand& f, const Vec3& x, const Vec3& w,
                     const std::optional<RayHit>& blocker) const {
        if (world_through_ == ~0u) return;
        if (blocker && !p_.scene.geometry().mesh(blocker->mesh).is_emissive()) return;
        const auto e = emitted_radiance(p_.scene.lights()[world_through_], x, w);
        if (!e) return;
        f.main -= e->radiance;
        f.hidden += e->radiance;
    }
    Integrand integrand(const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& w);
    // take_sample's shortcut for a light sample of integrand 0 (see there);
    // false: the sample still needs its densities.
    bool add_unlit_sample(std::size_t main_size, int main_index, int hidden_index,
                          double own_density, const Integrand& f, const Estimators* into,
                          int n_into);
    // integrand() where every light casts shadows (clip_at_blocker_, below
    // p_), from the closest hit first: of a direction a light technique drew
    // toward light `drawn` (at drawn_distance from x), or with drawn = ~0u of
    // a BSDF direction. Where the blocker hides the drawn light (or, for a
    // BSDF direction, where there is one), only the lights up to it are
    // listed, which are all that can be seen; where nothing is hit and every
    // shaped light is an emissive triangle of the geometry
    // (shapes_in_geometry_), only the unshaped lights (and the drawn one).
    // The same value as integrand(), but on the edges of light shapes
    // (a set of directions of measure zero).
    Integrand integrand_to_blocker(const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& w,
                                   std::uint32_t drawn, double drawn_distance);
    // The radiance of the mesh lights among `lights` whose mesh is the
    // closest hit along w (`blocker`), added to f (before the closure).
    void add_mesh_lights_seen(Integrand& f, const std::vector<std::uint32_t>& lights,
                              const std::optional<RayHit>& blocker) const {
        if (!blocker || !p_.scene.geometry().mesh(blocker->mesh).is_emissive()) return;
        for (std::uint32_t l : lights) {
            const Light& light = p_.scene.lights()[l];
            if (light.type == LightType::Mesh && light.mesh == blocker->mesh)
                (light.visible_to_bsdf ? f.main : f.hidden) += light.emission;
        }
    }
    // Light l's own part of the integrand along w (visible from x or not).
    Integrand light_integrand(std::uint32_t l, const Vec3& x, const Vec3& n, const Vec3& ng,
                              const Vec3& w);
    // light_integrand before its shadow ray: light l's radiance toward x
    // along w, the receiver's cosine factor and the emitting point's
    // distance; none where w is below x's horizon or l sends nothing along it.
    struct Unoccluded {
        Vec3 radiance;
        double cosine_factor, distance;
    };
    std::optional<Unoccluded> light_unoccluded(std::uint32_t l, const Vec3& x, const Vec3& n,
                                               const Vec3& w) const;
    // Whether a shadow ray from x along w meets something before light l's
    // emitting point `distance` away (false where no shadow rays are traced);
    // for a mesh light, whether the closest hit is off its mesh.
    bool light_occluded(std::uint32_t l, const Vec3& x, const Vec3& ng, const Vec3& w,
                        double distance);
    // Starts reading the first two cache lines of light l's record, all that
    // an emissive triangle's sample reads (light.h).
    void prefetch_light(std::uint32_t l) const { prefetch_record(&p_.scene.lights()[l]); }
    // GeometryScene::ListedLight: light l's record and its tree pmf's.
    static void prefetch_listed(void* self, std::uint32_t l) {
        const Impl& impl = *static_cast<const Impl*>(self);
        impl.prefetch_light(l);
        if (impl.p_.tree_selector) impl.p_.tree_selector->prefetch(l);
    }
    double technique_pdf(int k, const Vec3& x, const Vec3& n, const Vec3& w);
    bool choose_lights(int k, const Vec3& x, const Vec3& n);
    // choose_lights' per-point table for a whole footprint (its probes: the
    // centre and corners), so a light that reaches part of a texel keeps its
    // share wherever in the texel it was probed.
    // A footprint's probes for its tables and region: the centre, and its
    // corners made only when first asked (most lights reach the centre, and
    // then no corner is looked at).
    class Probes {
    public:
        Probes(const SurfacePoint& centre, const Footprint* footprint)
            : footprint_(footprint), corners_ready_(!footprint) {
            p_[0] = centre;
        }
        int count() const { return footprint_ ? 5 : 1; }
        const SurfacePoint& operator[](int i) {
            if (i > 0 && !corners_ready_) {
                int j = 1;
                for (double u : {0.0, 1.0})
                    for (double v : {0.0, 1.0}) p_[j++] = footprint_->at(u, v);
                corners_ready_ = true;
            }
            return p_[i];
        }

    private:
        const Footprint* footprint_;
        bool corners_ready_;
        SurfacePoint p_[5];
    };
    // kept: the point's reach for technique k (LightingContext::table_reach),
    // null where none is kept.
    bool choose_lights_over(int k, Probes& probes, std::uint8_t* kept);
    // reaches_: per slot of technique k's table, whether its light reaches
    // some probe (as the table's maker found).
    void mix_in_uniform(int k);
    std::vector<char> reaches_;
    // `unoccluded` weights at the footprint's anchor (Footprint::table_anchor),
    // shared by the texels of its block: kept for the last kAnchorSlots
    // anchors seen (a tile's row of texels crosses several blocks), per
    // integrated light (index into p_.integrated), NaN until asked.
    struct AnchorWeights {
        bool used = false;
        Footprint::Anchor anchor;
        std::vector<double> irradiance;
    };
    static constexpr int kAnchorSlots = 8;
    AnchorWeights anchors_[kAnchorSlots];
    AnchorWeights* anchor_ = nullptr;  // the footprint being set up's; null: none
    int next_anchor_slot_ = 0;
    void set_anchor(const Footprint* footprint);
    double centre_weight(std::size_t i, const SurfacePoint& centre);
    // Every integrated light direction w from x may cross (a superset: area
    // lights from the Embree shape scene, plus the few unshaped ones).
    const std::vector<std::uint32_t>& lights_along(const Vec3& x, const Vec3& w);
    // The shape pdf of each light in `along` = lights_along(x, w) (the
    // caller's, got once) for `sampler`: kept for the direction, as
    // techniques that share a sampler (tree/… and power/…) ask for the same
    // values.
    const std::vector<double>& shape_pdfs_along(const std::vector<std::uint32_t>& along,
                                                ShapeSampler sampler, const Vec3& x,
                                                const Vec3& n, const Vec3& w);
    MisEstimator& estimator(std::unordered_map<std::uint64_t, MisEstimator>& cache,
                            std::uint64_t key, const std::vector<int>& active,
                            const int* counts, bool fresh);

    // Spherical rectangles/triangles and elliptic cones depend on the point
    // only: build each once per point instead of once per sample and pdf
    // evaluation (an ellipse's cone takes a Jacobi orthogonalisation: 39 % of a
    // spread-disk bake when built per evaluation). Skipped for scenes with
    // very many lights, where the table would not pay.
    struct SolidAngleCache {
        std::uint64_t point = ~0ull;
        Vec3 n;  // the receiver normal the warp was made for
        std::optional<CosineWarped<SphericalRect>> rect;
        std::optional<CosineWarped<SphericalTriangle>> triangle;
        std::optional<SphericalEllipse> ellipse;
    };
    static constexpr std::size_t kMaxCachedLights = 1024;
    const SolidAngleCache* solid_angle(std::uint32_t l, const Vec3& x, const Vec3& n);
    bool solid_angle_ready(std::uint32_t l) const {
        return l < solid_angle_cache_.size() && solid_angle_cache_[l].point == point_serial_;
    }
    std::optional<LightSample> sample(std::uint32_t l, ShapeSampler sampler, const Vec3& x,
                                      const Vec3& n, double u1, double u2);
    // Whether light l (`light`) is tiny in solid angle at x (kTinySolidAngle).
    bool tiny(std::uint32_t l, const Light& light, const Vec3& x) const {
        if (p_.tiny_shapes.empty()) return tiny_in_solid_angle(tiny_shape_of(light), x);
        return tiny_in_solid_angle(p_.tiny_shapes[l], x);
    }
    static std::optional<LightSample> sample_cached(const SolidAngleCache& c, double u1,
                                                    double u2);
    // A triangle light's hit test along a direction, once made (or not).
    struct TriangleTest {
        bool known = false;
        std::optional<ShapeHit> hit;
    };
    // known: light l's hit test along w, where made (Along::tests).
    double pdf(std::uint32_t l, ShapeSampler sampler, const Vec3& x, const Vec3& n,
               const Vec3& w, const TriangleTest* known = nullptr);
    std::vector<SolidAngleCache> solid_angle_cache_;
    std::uint64_t point_serial_ = 0;

    const LightingContext& p_;
    LightingCounters& counters;
    std::vector<LightChoice> choices_;  // per technique (light techniques only)
    std::unordered_map<std::uint64_t, MisEstimator> main_cache_, hidden_cache_;
    struct Hit {
        std::uint32_t light;
        Emitted emitted;
    };
    std::vector<Hit> hits_;
    struct Along {
        Vec3 x, w;
        bool valid = false;
        std::vector<std::uint32_t> lights;
        // Per light of `lights`, its triangle's hit test along w where
        // integrand_to_blocker made it (valid while along_serial_ = tested):
        // the shape's area density takes it instead of a second test (~140
        // instructions a sample among emissive triangles).
        std::vector<TriangleTest> tests;
        std::uint64_t tested = 0;
    } along_;
    struct ShapePdfs {
        std::uint64_t along = 0;  // along_serial_ they were evaluated for
        ShapeSampler sampler = ShapeSampler::Area;
        Vec3 n;
        std::vector<double> pdf;  // per light in along_.lights
    } shape_pdfs_;
    std::uint64_t along_serial_ = 0;  // counts along_'s recomputations
    // Whether along_ lists the lights along (x, w) already.
    bool along_is(const Vec3& x, const Vec3& w) const {
        const Along& a = along_;
        return a.valid && a.x.x == x.x && a.x.y == x.y && a.x.z == x.z && a.w.x == w.x &&
               a.w.y == w.y && a.w.z == w.z;
    }
    // A table technique's density along a direction whose lights are not
    // listed yet: up to this many lights, a loop over the table's (a shape
    // test each, ~200 instructions) costs less than listing them (an Embree
    // query of the emitter shapes).
    static constexpr std::size_t kFewTableLights = 4;
    // technique_pdf's table slots along w, each with its light's index in
    // along_.lights (for its hit test, Along::tests).
    std::vector<std::pair<std::size_t, std::size_t>> along_slots_;
    // The last light sample: its light surely lies along its direction, and
    // its shape density there is the one the draw returned — pdf() reuses it
    // instead of inverting the draw (~10 % of a solid-angle sample) where the
    // weights are continuous in the densities (reuse_drawn_pdf_), so that a
    // last-digit difference from the evaluated density changes nothing. The
    // maximum and cutoff heuristics compare densities (exact ties where two
    // techniques share a density), so there every density stays one function
    // of the direction, whichever technique drew it.
    struct Drawn {
        std::uint32_t light = ~0u;
        Vec3 w;
        // The technique's (a tiny light's draw used Area: pdf() repeats the
        // choice from the light and the point).
        ShapeSampler sampler = ShapeSampler::Area;
        double pdf = 0;
        std::uint64_t point = ~0ull;  // point_serial_ of the draw
    } drawn_;
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
    // integrand_to_blocker applies (set after p_). Among emissive triangles:
    // with analytic lights alone, integrand() often needs only an occlusion
    // ray, cheaper than a closest hit.
    const bool clip_at_blocker_ =
        p_.settings.fast_paths && p_.plan.shadow_rays &&
        std::all_of(p_.scene.lights().begin(), p_.scene.lights().end(),
                    [](const Light& l) { return l.cast_shadow; }) &&
        std::any_of(p_.scene.lights().begin(), p_.scene.lights().end(),
                    [](const Light& l) { return l.type == LightType::Triangle; });
    // The scene's (first) world light, else ~0u.
    const std::uint32_t world_light_ = [this] {
        for (std::uint32_t l = 0; l < p_.scene.lights().size(); ++l)
            if (p_.scene.lights()[l].type == LightType::World) return l;
        return ~0u;
    }();
    // BSDF directions too take integrand_to_blocker where a world lies along
    // every one of them: integrand() then traces a ray for each anyway, after
    // an all-hits query of the emitter shapes that the closest hit makes
    // unneeded where it meets a surface that does not emit or, with
    // shapes_in_geometry_, nothing.
    const bool bsdf_to_blocker_ = clip_at_blocker_ && world_light_ != ~0u;
    // The world light when the plan sees it through emitters, else ~0u.
    const std::uint32_t world_through_ = p_.plan.world_through_emitters ? world_light_ : ~0u;
    // Every light with an emitter shape is an emissive triangle, which the
    // geometry holds: a ray that meets no surface crosses no such shape.
    const bool shapes_in_geometry_ = std::all_of(
        p_.scene.lights().begin(), p_.scene.lights().end(), [&](const Light& l) {
            return l.is_delta() || l.type == LightType::Triangle ||
                   std::find(p_.scene.unshaped_lights().begin(), p_.scene.unshaped_lights().end(),
                             std::uint32_t(&l - p_.scene.lights().data())) !=
                       p_.scene.unshaped_lights().end();
        });
    std::vector<std::uint32_t> clipped_;  // integrand_to_blocker's lights
    std::vector<std::uint32_t> merged_;   // ... from the closest hit's traversal
    // Every light technique's table (if any) has weights that need no
    // irradiance (`uniform`, `power`: only which lights reach the probes):
    // active_for makes them again at every pass instead of keeping them in
    // the texel tables, which costs three allocations per texel, their
    // release at the end and a lookup per pass. Measured on the
    // emission_world reproduction (omis module, 128², one thread, CPU per
    // bake, best of 5 interleaved runs of 10): samples=2 42 → 34 ms;
    // samples=64 unchanged within the noise (±10 %).
    const bool cheap_tables_ = !p_.keeps_texel_tables;
    const bool reuse_drawn_pdf_ = p_.settings.strategy != Strategy::Maximum &&
                                  p_.settings.strategy != Strategy::Cutoff;
    // `sampler`: the technique's, before the tiny-light substitution (the
    // draw made it for the same light and point).
    bool drawn_density(std::uint32_t l, ShapeSampler sampler, const Vec3& w, double& pdf) const {
        if (!reuse_drawn_pdf_ || drawn_.light != l || drawn_.point != point_serial_ || drawn_.sampler != sampler ||
            drawn_.w.x != w.x || drawn_.w.y != w.y || drawn_.w.z != w.z)
            return false;
        pdf = drawn_.pdf;
        return true;
    }
    LightSelector::Memo memo_, delta_memo_;  // the trees' branching at the current point
    // The light the sample being taken drew from `selector` at its position,
    // and the pmf the draw formed: its density takes that pmf, which the
    // memo does not hold for a light drawn ahead (SelectorDraw). The same
    // product pmf() would form.
    struct DrawnSelection {
        const LightSelector* selector = nullptr;
        std::uint32_t light = ~0u;
        double pmf = 0;
    } drawn_selection_;
    // The texel being shaded as a region (LightSelector::Receiver): a ball
    // about its centre through its footprint's corners (radius 0: none).
    // Selectors draw with the region's pmfs at every sample inside it — one
    // set per texel, kept in region_memo_ — instead of walking the tree
    // afresh at each sample's own position.
    LightSelector::Receiver region_;
    LightSelector::Memo region_memo_;
    // point: the shading's stream, whose radius the context may keep
    // (LightingContext::region_radii).
    void set_region(std::uint64_t point, Probes& probes);
    LightSelector::Receiver receiver_at(const Vec3& x, const Vec3& n,
                                        LightSelector::Memo*& memo);
};

const PointLighting::Impl::SolidAngleCache* PointLighting::Impl::solid_angle(std::uint32_t l,
                                                                             const Vec3& x,
                                                                             const Vec3& n) {
    const Light& light = p_.scene.lights()[l];
    if (light.type != LightType::Rect && light.type != LightType::Triangle &&
        !ellipse_wholly_reaches(light, x))
        return nullptr;  // a spread ellipse's part is drawn by area
    if (p_.scene.lights().size() > kMaxCachedLights) return nullptr;
    if (solid_angle_cache_.size() != p_.scene.lights().size())
        solid_angle_cache_.resize(p_.scene.lights().size());
    SolidAngleCache& c = solid_angle_cache_[l];
    if (c.point != point_serial_ || c.n.x != n.x || c.n.y != n.y || c.n.z != n.z) {
        c.point = point_serial_;
        c.n = n;
        // RectLight/TriangleLight::sample_solid_angle(x, n, …)'s shape, prepared.
        c.rect.reset();
        c.triangle.reset();
        c.ellipse.reset();
        if (light.type == LightType::Rect) {
            const auto r = rect_reaching(light, x);  // spread: only the part that reaches x
            const auto s = r ? SphericalRect::make(x, r->corner, r->edge_u, r->edge_v)
                             : std::nullopt;
            if (s) c.rect.emplace(*s, n);
        } else if (light.type == LightType::Ellipse) {
            const EllipseLight& e = light.ellipse;
            c.ellipse = SphericalEllipse::make(x, e.center, e.axis_a, e.axis_b);
        } else if (const auto s = SphericalTriangle::make(x, light.triangle.p0,
                                                          light.triangle.p1, light.triangle.p2)) {
            c.triangle.emplace(*s, n);
        }
    }
    return &c;
}

std::optional<LightSample> PointLighting::Impl::sample(std::uint32_t l, ShapeSampler sampler,
                                                       const Vec3& x, const Vec3& n, double u1,
                                                       double u2) {
    const Light& light = p_.scene.lights()[l];
    const ShapeSampler asked = sampler;
    if (sampler == ShapeSampler::SolidAngle && tiny(l, light, x))
        sampler = ShapeSampler::Area;
    const SolidAngleCache* c =
        sampler == ShapeSampler::SolidAngle ? solid_angle(l, x, n) : nullptr;
    std::optional<LightSample> s;
    if (!c) s = sample_light(light, sampler, x, n, u1, u2);
    else s = sample_cached(*c, u1, u2);
    if (s) drawn_ = {l, s->dir, asked, s->pdf, point_serial_};
    return s;
}

std::optional<LightSample> PointLighting::Impl::sample_cached(const SolidAngleCache& cache,
                                                              double u1, double u2) {
    // RectLight/TriangleLight::sample_solid_angle's draw, from the prepared shape.
    if (cache.rect) return warped_solid_angle_sample(*cache.rect, u1, u2);
    if (cache.triangle) return warped_solid_angle_sample(*cache.triangle, u1, u2);
    if (cache.ellipse) {  // EllipseLight::sample_solid_angle's draw
        const DirSample s = cache.ellipse->sample(u1, u2);
        return LightSample{s.dir, s.dist, cache.ellipse->pdf(s.dir)};
    }
    return std::nullopt;
}

double PointLighting::Impl::pdf(std::uint32_t l, ShapeSampler sampler, const Vec3& x,
                                const Vec3& n, const Vec3& w, const TriangleTest* known) {
    // The sample's own density, before the light's record is read again
    // for the tiny-light test (the draw made the same choice).
    double drawn;
    if (drawn_density(l, sampler, w, drawn)) return drawn;
    const Light& light = p_.scene.lights()[l];
    if (sampler == ShapeSampler::SolidAngle && tiny(l, light, x))
        sampler = ShapeSampler::Area;
    // Its triangle's hit test along w, where made: TriangleLight::intersect,
    // as pdf_area and ray_crosses_light make it.
    const bool tested = known && known->known && light.type == LightType::Triangle;
    if (tested && sampler == ShapeSampler::Area)
        return light.triangle.pdf_area_at(known->hit, w, light.triangle_area);
    // A direction that misses the light has density 0 there: no need to
    // prepare its shape at x (the hit test's slack keeps the edge).
    if (sampler == ShapeSampler::SolidAngle && !solid_angle_ready(l) &&
        !(tested ? known->hit.has_value() : ray_crosses_light(light, x, w)))
        return 0.0;
    const SolidAngleCache* c =
        sampler == ShapeSampler::SolidAngle ? solid_angle(l, x, n) : nullptr;
    if (!c) return light_pdf(light, sampler, x, n, w);
    if (c->rect) return c->rect->pdf(w);
    if (c->triangle) return c->triangle->pdf(w);
    if (c->ellipse) return c->ellipse->pdf(w);
    return 0.0;
}

// Whether technique k has a light to draw at (x, n). `tree` (and `uniform`,
// `power` among many lights) draws from the context's selectors, which need
// no per-point setup; otherwise a table over the lights that reach x is made
// here (`unoccluded`: by their exact unoccluded irradiance). A technique
// with no light to draw at x leaves the point's MIS system.
bool PointLighting::Impl::choose_lights(int k, const Vec3& x, const Vec3& n) {
    const Technique& t = p_.settings.techniques[k];
    if (const LightSelector* s = p_.selector(t.selection)) {
        if (s->empty() || !s->may_reach(x, n)) return false;
        if (p_.integrated.size() > std::size_t(kManyIntegratedLights)) return true;
        for (std::uint32_t l : p_.integrated)
            if (sampler_applies(p_.scene.lights()[l], t.sampler, x, n)) return true;
        return false;
    }
    LightChoice& c = choices_[k];
    c.lights.clear();
    c.probability.clear();
    c.cdf.clear();
    double total = 0, largest = 0;
    for (std::uint32_t l : p_.integrated) {
        const Light& light = p_.scene.lights()[l];
        if (!sampler_applies(light, t.sampler, x, n)) continue;
        double w = 1.0;
        if (t.selection == LightSelection::Power) w = p_.power[l];
        if (t.selection == LightSelection::Unoccluded || t.selection == LightSelection::Defensive)
            w = unoccluded_irradiance(light, x, n);
        c.lights.push_back(l);
        c.probability.push_back(w);
        largest = std::max(largest, w);
    }
    // A light that reaches x but whose weight rounds to zero keeps a tiny share,
    // so every direction the integrand covers stays sampleable.
    for (double& w : c.probability) {
        if (!(w > 0)) w = largest > 0 ? 1e-9 * largest : 1.0;
        total += w;
    }
    double running = 0;
    for (double& w : c.probability) {
        w /= total;
        running += w;
        c.cdf.push_back(running);
    }
    if (!c.cdf.empty()) c.cdf.back() = 1.0;
    if (t.selection == LightSelection::Defensive) {
        reaches_.assign(c.lights.size(), 1);  // the table holds the lights that reach x
        mix_in_uniform(k);
    }
    return !c.lights.empty();
}

// The table covers a texel's footprint, not just its centre: a light that
// reaches the centre weighs what it does there (`unoccluded`: its unoccluded
// irradiance), one that reaches only some corners the mean over the probes
// (probes[0] is the centre), and every other light keeps the tiny share, so a
// light that reaches only the inside of the footprint is still drawn
// (unbiased wherever the technique is active). A table made at the centre
// alone dropped a light from every texel whose centre it did not reach — the
// rim of a spread light's reach, the plane of a one-sided light. Corners are
// probed only for lights that miss the centre: the weights cost per pass.
//
// Where the weights need no irradiance (`uniform`, `power`), the table is
// made from which probes each light reaches, which a kept texel has from its
// first pass: kept[i] = 1 + the probes light i weighs over (n_probes where
// it reaches the centre), 0 before. The weights then take the same sums in
// the same order: the same table, bit for bit, without probing again.
bool PointLighting::Impl::choose_lights_over(int k, Probes& probes, std::uint8_t* kept) {
    const int n_probes = probes.count();
    const Technique& t = p_.settings.techniques[k];
    LightChoice& c = choices_[k];
    c.lights.clear();
    c.probability.clear();
    c.cdf.clear();
    auto weight = [&](std::uint32_t l, const SurfacePoint& p) {
        if (t.selection == LightSelection::Power) return p_.power[l];
        if (t.selection == LightSelection::Unoccluded || t.selection == LightSelection::Defensive)
            return unoccluded_irradiance(p_.scene.lights()[l], p.x, p.n);
        return 1.0;
    };
    const bool by_irradiance =
        t.selection == LightSelection::Unoccluded || t.selection == LightSelection::Defensive;
    bool any = false;
    double largest = 0;
    reaches_.assign(p_.integrated.size(), 0);
    if (by_irradiance) kept = nullptr;
    const bool from_kept = kept && kept[0] != 0;
    for (std::size_t i = 0; i < p_.integrated.size(); ++i) {
        const std::uint32_t l = p_.integrated[i];
        const Light& light = p_.scene.lights()[l];
        double w = 0;
        if (from_kept) {
            const int reached = kept[i] - 1;
            if (reached == n_probes)
                w = weight(l, probes[0]);
            else  // the same at every probe: the centre's
                for (int j = 0; j < reached; ++j) w += weight(l, probes[0]) / n_probes;
            reaches_[i] = reached > 0;
        } else if (sampler_applies(light, t.sampler, probes[0].x, probes[0].n)) {
            w = by_irradiance ? centre_weight(i, probes[0]) : weight(l, probes[0]);
            reaches_[i] = 1;
            if (kept) kept[i] = std::uint8_t(1 + n_probes);
        } else {
            int reached = 0;
            for (int j = 1; j < n_probes; ++j)
                if (sampler_applies(light, t.sampler, probes[j].x, probes[j].n)) {
                    w += weight(l, probes[j]) / n_probes;
                    reaches_[i] = 1;
                    ++reached;
                }
            if (kept) kept[i] = std::uint8_t(1 + reached);
        }
        any = any || reaches_[i];
        c.lights.push_back(l);
        c.probability.push_back(w);
        largest = std::max(largest, w);
    }
    if (!any) return false;
    double total = 0, running = 0;
    for (double& w : c.probability) {
        if (!(w > 0)) w = largest > 0 ? 1e-9 * largest : 1.0;
        total += w;
    }
    for (double& w : c.probability) {
        w /= total;
        running += w;
        c.cdf.push_back(running);
    }
    c.cdf.back() = 1.0;
    if (t.selection == LightSelection::Defensive) mix_in_uniform(k);
    return true;
}

// `defensive` selection: technique k's table (unoccluded probabilities) becomes
// half that and half uniform over the lights that reach some probe, so a light
// the unoccluded weights undervalue — one shadowed where it is bright — keeps
// a fair share of a single technique's samples. Lights reaching no probe keep
// their tiny share (unbiased wherever the technique is active).
// With a world among the lights, the uniform part is kDefensiveShareWithWorld
// instead of half: the world is drawn by cosine over the whole hemisphere, and
// its draws are the noisy ones wherever it is partly hidden (each finds it with
// the probability of its visible cosine-weighted share: a skylight, a window),
// while a lamp's solid-angle draws are nearly exact where it is seen; half
// uniform gave the lamps as many draws as the world. Measured per sample
// (omis-module reproductions of the race's scenes, 64², optimal, 8–16 seeds,
// relMSE at 2/4/16/64/256 spp against a half): world_window (a skylit room,
// world 29× the lamp's power) 1.04/1.03/0.80/0.75/0.64 (a quarter:
// 0.91/0.92/0.85/0.83/0.78; none, i.e. `unoccluded`: 1.64/1.64/1.28/0.82/0.62,
// as a light drawn a few percent of the time is missed by most texels' first
// draws); emission_world with a world 10× as bright (then the main light, in
// the open) 0.41/0.48/0.49 at 4/16/256 spp (`unoccluded` 0.28/0.38/0.39).
void PointLighting::Impl::mix_in_uniform(int k) {
    LightChoice& c = choices_[k];
    const std::vector<char>& reaches = reaches_;
    int reaching = 0;
    bool world = false;
    for (std::size_t i = 0; i < c.lights.size(); ++i) {
        reaching += reaches[i];
        world = world || p_.scene.lights()[c.lights[i]].type == LightType::World;
    }
    if (reaching == 0) return;
    const double uniform = world ? kDefensiveShareWithWorld : 0.5;
    double running = 0;
    for (std::size_t i = 0; i < c.lights.size(); ++i) {
        c.probability[i] =
            (1 - uniform) * c.probability[i] + (reaches[i] ? uniform / reaching : 0.0);
        running += c.probability[i];
        c.cdf[i] = running;
    }
    // The probabilities still sum to 1 (up to rounding): the CDF's end is exact.
    c.cdf.back() = 1.0;
}

// The anchor of the footprint being set up; its weights are kept while the
// next footprints name the same anchor (a block's texels, shaded in a row).
void PointLighting::Impl::set_anchor(const Footprint* footprint) {
    Footprint::Anchor a;
    anchor_ = nullptr;
    if (!footprint || !footprint->table_anchor(a)) return;
    for (AnchorWeights& slot : anchors_) {
        const Footprint::Anchor& kept = slot.anchor;
        if (slot.used && kept.id == a.id && kept.at.x.x == a.at.x.x &&
            kept.at.x.y == a.at.x.y && kept.at.x.z == a.at.x.z && kept.at.n.x == a.at.n.x &&
            kept.at.n.y == a.at.n.y && kept.at.n.z == a.at.n.z) {
            anchor_ = &slot;
            return;
        }
    }
    anchor_ = &anchors_[next_anchor_slot_];
    next_anchor_slot_ = (next_anchor_slot_ + 1) % kAnchorSlots;
    anchor_->used = true;
    anchor_->anchor = a;
    anchor_->irradiance.assign(p_.integrated.size(), std::numeric_limits<double>::quiet_NaN());
}

// The `unoccluded` weight of integrated light i for a footprint whose centre
// it reaches: its unoccluded irradiance at the anchor when it reaches that,
// else at the centre. A function of the anchor and the centre only, so every
// pass and thread makes the same table.
double PointLighting::Impl::centre_weight(std::size_t i, const SurfacePoint& centre) {
    const Light& light = p_.scene.lights()[p_.integrated[i]];
    if (anchor_) {
        double& w = anchor_->irradiance[i];
        if (std::isnan(w)) w = unoccluded_irradiance(light, anchor_->anchor.at.x, anchor_->anchor.at.n);
        if (w > 0) return w;
    }
    return unoccluded_irradiance(light, centre.x, centre.n);
}

// The selection takes u1 of the shape's pair, and the shape its rest within
// the chosen light's share (SelectedLight::rest), as Cycles does: the draws
// that choose one light then keep the pair's 2-D stratification, where an
// independent selection dimension left each light a random subset of it.
// Group 1 fills u1's bits below its 32 (u1 then uniform on [0, 1) and its
// rest keeps them). Measured per sample on the emissive_mesh race scene (the
// sphere hiding part of the square light): relMSE 0.74×, 0.54×, 0.34× at 16,
// 64, 256 samples, most in the penumbra (bench/results/error_sources.txt,
// 2026-12-01).
void PointLighting::Impl::begin_selector_draw(int k, const ScrambledSobol& sequence,
                                              std::uint32_t index, const SurfacePoint& centre,
                                              const Footprint* footprint, SelectorDraw& d) {
    d.k = k;
    d.sequence = &sequence;
    d.index = index;
    d.selector = technique_selectors_[k];
    if (footprint) {
        double fu, fv;
        sequence.get_2d(index, 0, fu, fv);
        d.p = footprint->at(fu, fv);
    } else {
        d.p = centre;
    }
    sequence.get_2d(index, 2, d.u1, d.u2);
    LightSelector::Memo* memo;
    const LightSelector::Receiver at = receiver_at(d.p.x, d.p.n, memo);
    d.partial = d.selector->begin_draw(at, d.u1 + sequence.get_1d(index, 1) * 0x1.0p-32, memo);
    d.finished = false;
}

void PointLighting::Impl::finish_selector_draw(SelectorDraw& d) {
    if (d.finished) return;
    d.finished = true;
    d.light = d.selector->finish_draw(d.partial);
    if (d.light) d.u1 = d.light->rest;
}

const std::vector<std::uint32_t>& PointLighting::Impl::lights_along(const Vec3& x,
                                                                    const Vec3& w) {
    Along& a = along_;
    if (along_is(x, w)) return a.lights;
    a.x = x;
    a.w = w;
    a.valid = true;
    ++along_serial_;
    a.lights.clear();
    p_.scene.emitter_shapes().lights_along(x, w, a.lights);
    const auto& unshaped = p_.scene.unshaped_lights();
    a.lights.insert(a.lights.end(), unshaped.begin(), unshaped.end());
    // The light just sampled toward w lies along it, even where single
    // precision might miss its (enlarged) shape.
    if (drawn_.light != ~0u && drawn_.w.x == w.x && drawn_.w.y == w.y && drawn_.w.z == w.z &&
        std::find(a.lights.begin(), a.lights.end(), drawn_.light) == a.lights.end())
        a.lights.push_back(drawn_.light);
    return a.lights;
}

const std::vector<double>& PointLighting::Impl::shape_pdfs_along(
    const std::vector<std::uint32_t>& along, ShapeSampler sampler, const Vec3& x, const Vec3& n,
    const Vec3& w) {
    ShapePdfs& c = shape_pdfs_;
    if (c.along == along_serial_ && c.sampler == sampler && c.n.x == n.x && c.n.y == n.y &&
        c.n.z == n.z)
        return c.pdf;
    c.along = along_serial_;
    c.sampler = sampler;
    c.n = n;
    c.pdf.clear();
    const bool tested = &along == &along_.lights && along_.tested == along_serial_;
    for (std::size_t i = 0; i < along.size(); ++i)
        c.pdf.push_back(this->pdf(along[i], sampler, x, n, w, tested ? &along_.tests[i] : nullptr));
    counters.pdf_evaluations += along.size();
    return c.pdf;
}

PointLighting::Impl::Integrand PointLighting::Impl::integrand(const Vec3& x, const Vec3& n,
                                                              const Vec3& ng, const Vec3& w) {
    Integrand f;
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return f;
    hits_.clear();
    // Mesh lights whose bounding sphere w meets: the closest hit tells
    // whether their mesh is seen.
    bool meshes = false;
    for (std::uint32_t l : lights_along(x, w)) {
        const Light& light = p_.scene.lights()[l];
        if (light.type == LightType::Mesh) {
            meshes = meshes || (luminance(light.emission) > 0 && mesh_light_along(light, x, w));
            continue;
        }
        const auto e = emitted_radiance(light, x, w);
        if (e && luminance(e->radiance) > 0) hits_.push_back({l, *e});
    }
    if (hits_.empty() && !meshes) return f;

    const GeometryScene& geometry = p_.scene.geometry();
    const Vec3 origin = offset_ray_origin(x, ng, w);
    // Distances below are measured from the offset origin; the offset itself
    // can exceed a relative shortening (1/65536 m near the world origin).
    const double offset = length(origin - x);
    bool need_rays = false, only_analytic = true;
    for (const Hit& h : hits_) {
        const Light& light = p_.scene.lights()[h.light];
        need_rays = need_rays || light.cast_shadow;
        only_analytic = only_analytic && light.type != LightType::Triangle;
    }
    need_rays = need_rays && p_.plan.shadow_rays;

    // One analytic light: an occlusion ray up to it. Otherwise one closest-hit
    // ray decides for every light along w, and a hit on an emitting triangle
    // (or at its depth, on a coplanar neighbour) does not shadow it.
    std::optional<RayHit> blocker;
    bool single_blocked = false;
    const bool single = hits_.size() == 1 && only_analytic && world_through_ == ~0u && !meshes;
    if (need_rays || meshes) {
        ++counters.rays;
        if (single)
            single_blocked = geometry.occluded(origin, w, 0, hits_[0].emitted.distance - offset);
        else
            blocker = geometry.closest_hit(origin, w, 0, std::numeric_limits<double>::infinity());
    }
    auto visible = [&](const Hit& h) {
        const Light& light = p_.scene.lights()[h.light];
        if (!need_rays || !light.cast_shadow) return true;
        if (single) return !single_blocked;
        if (!blocker) return true;
        const double depth = h.emitted.distance - offset;
        if (light.type != LightType::Triangle) return blocker->t >= depth;
        if (blocker->mesh == light.mesh && blocker->triangle == light.mesh_triangle) return true;
        return blocker->t >= depth * (1 - kEmitterDepthTolerance);
    };
    for (const Hit& h : hits_) {
        if (!visible(h)) continue;
        (p_.scene.lights()[h.light].visible_to_bsdf ? f.main : f.hidden) += h.emitted.radiance;
    }
    if (meshes) add_mesh_lights_seen(f, lights_along(x, w), blocker);
    if (need_rays)
        split_world(f, x, w, blocker);
    // The receiver's closure (Lambert: cosθ/π), as Cycles' Diffuse bake sees it.
    const double closure = receiver_cosine_factor(p_.settings.receiver, cos_theta);
    f.main *= closure;
    f.hidden *= closure;
    return f;
}

PointLighting::Impl::Integrand PointLighting::Impl::integrand_to_blocker(
    const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& w, std::uint32_t drawn,
    double drawn_distance) {
    Integrand f;
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return f;
    const Vec3 origin = offset_ray_origin(x, ng, w);
    const double offset = length(origin - x);
    ++counters.rays;
    // The closest hit and, in one traversal, the lights along w: all of
    // them where nothing but emitters lies along w (`complete`), as a
    // light among emissive triangles is mostly seen or hidden by another.
    // Traced from the offset origin, as the closest hit: a light crossing
    // w between x and it (one touching x) is found only by lights_along().
    const GeometryScene& geometry = p_.scene.geometry();
    bool complete = false;
    std::optional<RayHit> blocker;
    merged_.clear();
    if (geometry.has_emitter_candidates()) {
        // The lights found are read next (their radiance, then their
        // shapes' densities and tree pmfs): among 100k lights each record is
        // a cache miss, started as the traversal lists the light (the far
        // side of a closed mesh is still to be traversed) instead of one
        // after another once it is done.
        blocker = geometry.closest_hit_and_emitters(origin, w, merged_, complete,
                                                    &Impl::prefetch_listed, this);
    } else
        blocker = geometry.closest_hit(origin, w, 0, std::numeric_limits<double>::infinity());
    // integrand()'s rule: whether the blocker hides a light at `distance`
    // from x (a triangle is not hidden by itself, nor by a coplanar
    // neighbour at its depth).
    auto hidden = [&](const Light& light, double distance) {
        if (!blocker) return false;
        const bool triangle = light.type == LightType::Triangle;
        if (triangle && blocker->mesh == light.mesh && blocker->triangle == light.mesh_triangle)
            return false;
        return !(blocker->t >= (distance - offset) * (triangle ? 1 - kEmitterDepthTolerance : 1.0));
    };
    // The drawn light seen, or hidden by an emitting surface (a closed
    // mesh's near side): the integrand is not 0, and its densities need
    // every light along w anyway — list them all at once.
    const bool drew_light = drawn != ~0u;
    const auto& unshaped = p_.scene.unshaped_lights();
    const std::vector<std::uint32_t>* along = &clipped_;
    if (complete) {
        // Every light along w: what lights_along(x, w) lists (the shapes the
        // traversal crossed, the unshaped lights, the drawn light), kept for
        // the densities (technique_pdf) as it would keep its own.
        sort_unique(merged_);
        if (!unshaped.empty()) merged_.insert(merged_.end(), unshaped.begin(), unshaped.end());
        if (drew_light && std::find(merged_.begin(), merged_.end(), drawn) == merged_.end())
            merged_.push_back(drawn);
        along_.x = x;
        along_.w = w;
        along_.valid = true;
        ++along_serial_;
        along_.lights.swap(merged_);
        along = &along_.lights;
    } else if (!blocker && shapes_in_geometry_) {
        // Nothing hit: no emissive triangle lies along w (but the drawn one,
        // where single precision missed its edge), only the unshaped lights.
        clipped_.assign(unshaped.begin(), unshaped.end());
        if (drew_light && std::find(clipped_.begin(), clipped_.end(), drawn) == clipped_.end())
            clipped_.push_back(drawn);
    } else if (drew_light ? !hidden(p_.scene.lights()[drawn], drawn_distance) ||
                                p_.scene.geometry().mesh(blocker->mesh).is_emissive()
                          : !blocker || p_.scene.geometry().mesh(blocker->mesh).is_emissive()) {
        along = &lights_along(x, w);
    } else {
        // Hidden: no light past the blocker is seen, at most
        // blocker->t / (1 − tolerance) + offset from x. The emitter shapes'
        // distances are single precision: a margin far above their rounding
        // (relative to the coordinates' size) keeps every such light listed.
        const double reach = blocker->t / (1 - kEmitterDepthTolerance) + offset;
        const double scale = std::max({std::abs(x.x), std::abs(x.y), std::abs(x.z), reach});
        clipped_.clear();
        p_.scene.emitter_shapes().lights_along(x, w, clipped_, reach * (1 + 1e-4) + 1e-5 * scale);
        // Unshaped lights (a world, a sun's disk, a point light's) are listed
        // by no shape: `hidden` below judges them by their distance.
        clipped_.insert(clipped_.end(), unshaped.begin(), unshaped.end());
        // As lights_along(): the drawn light surely lies along w.
        if (drew_light && std::find(clipped_.begin(), clipped_.end(), drawn) == clipped_.end())
            clipped_.push_back(drawn);
    }
    // The triangles' hit tests kept for their densities (Along::tests).
    const bool keep_tests = along == &along_.lights;
    if (keep_tests) {
        along_.tests.resize(along->size());
        along_.tested = along_serial_;
    }
    for (std::size_t i = 0; i < along->size(); ++i) {
        const Light& light = p_.scene.lights()[(*along)[i]];
        std::optional<Emitted> e;
        if (light.type == LightType::Mesh) {
            if (keep_tests) along_.tests[i].known = false;
            continue;  // below, from the blocker
        }
        if (light.type == LightType::Triangle) {
            // Hidden first: the triangles behind the blocker (a closed mesh's
            // far side, about one a sample) need no radiance.
            const auto hit = light.triangle.intersect(x, w);
            if (keep_tests) along_.tests[i] = {true, hit};
            if (!hit || hidden(light, hit->t)) continue;
            e = triangle_emitted(light, w, hit->t);
        } else {
            if (keep_tests) along_.tests[i].known = false;
            e = emitted_radiance(light, x, w);
        }
        if (!e || !(luminance(e->radiance) > 0) || hidden(light, e->distance)) continue;
        (light.visible_to_bsdf ? f.main : f.hidden) += e->radiance;
    }
    add_mesh_lights_seen(f, *along, blocker);
    split_world(f, x, w, blocker);
    const double closure = receiver_cosine_factor(p_.settings.receiver, cos_theta);
    f.main *= closure;
    f.hidden *= closure;
    return f;
}

PointLighting::Impl::Integrand PointLighting::Impl::light_integrand(std::uint32_t l,
                                                                    const Vec3& x,
                                                                    const Vec3& n,
                                                                    const Vec3& ng,
                                                                    const Vec3& w) {
    Integrand f;
    const auto u = light_unoccluded(l, x, n, w);
    if (!u || light_occluded(l, x, ng, w, u->distance)) return f;
    (p_.scene.lights()[l].visible_to_bsdf ? f.main : f.hidden) = u->radiance * u->cosine_factor;
    return f;
}

std::optional<PointLighting::Impl::Unoccluded> PointLighting::Impl::light_unoccluded(
    std::uint32_t l, const Vec3& x, const Vec3& n, const Vec3& w) const {
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return std::nullopt;
    const Light& light = p_.scene.lights()[l];
    if (light.type == LightType::Mesh) {
        // Its emission wherever w may meet its mesh: light_occluded then
        // tells whether the closest hit is on it.
        if (!mesh_light_along(light, x, w) || !(luminance(light.emission) > 0)) return std::nullopt;
        return Unoccluded{light.emission, receiver_cosine_factor(p_.settings.receiver, cos_theta),
                          std::numeric_limits<double>::infinity()};
    }
    const auto e = emitted_radiance(light, x, w);
    if (!e || !(luminance(e->radiance) > 0)) return std::nullopt;
    return Unoccluded{e->radiance, receiver_cosine_factor(p_.settings.receiver, cos_theta),
                      e->distance};
}

bool PointLighting::Impl::light_occluded(std::uint32_t l, const Vec3& x, const Vec3& ng,
                                         const Vec3& w, double distance) {
    const Light& light = p_.scene.lights()[l];
    if (light.type == LightType::Mesh) {
        // Seen where the closest hit is on its mesh (its mesh is the
        // emitter: a ray is traced whatever the plan says of shadows).
        ++counters.rays;
        const auto hit = p_.scene.geometry().closest_hit(offset_ray_origin(x, ng, w), w, 0,
                                                         std::numeric_limits<double>::infinity());
        return !hit || hit->mesh != light.mesh;
    }
    if (!p_.plan.shadow_rays || !light.cast_shadow) return false;
    // Up to the emitting point; a triangle's own surface (or a coplanar
    // neighbour at its depth) does not shadow it, as in integrand().
    const Vec3 origin = offset_ray_origin(x, ng, w);
    double depth = distance - length(origin - x);
    if (light.type == LightType::Triangle) depth *= 1 - kEmitterDepthTolerance;
    ++counters.rays;
    return p_.scene.geometry().occluded(origin, w, 0, depth);
}

double PointLighting::Impl::technique_pdf(int k, const Vec3& x, const Vec3& n, const Vec3& w) {
    const Technique& t = p_.settings.techniques[k];
    if (t.bsdf) return std::max(0.0, dot(n, w)) * kInvPi;
    if (const LightSelector* s = technique_selectors_[k]) {
        // Only lights along w have a density there. Their pmf records are
        // read while their shapes' densities are computed.
        const std::vector<std::uint32_t>& along = lights_along(x, w);
        for (std::uint32_t l : along) s->prefetch(l);
        double pdf = 0;
        const std::vector<double>& shape = shape_pdfs_along(along, t.sampler, x, n, w);
        LightSelector::Memo* memo;
        const LightSelector::Receiver at = receiver_at(x, n, memo);
        for (std::size_t i = 0; i < along.size(); ++i) {
            // The shape's density first: it is 0 for most extra candidates,
            // and then the tree need not be walked.
            if (!(shape[i] > 0)) continue;
            const DrawnSelection& d = drawn_selection_;
            pdf += (s == d.selector && along[i] == d.light ? d.pmf : s->pmf(at, along[i], memo)) *
                   shape[i];
        }
        return pdf;
    }
    const LightChoice& c = choices_[k];
    double pdf = 0;
    if (p_.settings.fast_paths && (along_is(x, w) || c.lights.size() > kFewTableLights)) {
        // As the selectors: only lights along w have a density there (the
        // sphere's near and far triangle, of 16), and a loop over the table
        // tested every light's shape (~29 % of a sample at 16 emitters).
        // The terms summed in the table's order, the others being 0: the
        // loop's sum, bit for bit.
        along_slots_.clear();
        const std::vector<std::uint32_t>& along = lights_along(x, w);
        for (std::size_t j = 0; j < along.size(); ++j) {
            // A table lists its lights in p_.integrated's (ascending) order.
            const auto it = std::lower_bound(c.lights.begin(), c.lights.end(), along[j]);
            if (it != c.lights.end() && *it == along[j])
                along_slots_.push_back({std::size_t(it - c.lights.begin()), j});
        }
        std::sort(along_slots_.begin(), along_slots_.end());
        const bool tested = along_.tested == along_serial_;
        for (const auto& [i, j] : along_slots_)
            pdf += c.probability[i] *
                   this->pdf(c.lights[i], t.sampler, x, n, w, tested ? &along_.tests[j] : nullptr);
        counters.pdf_evaluations += along_slots_.size();
        return pdf;
    }
    for (std::size_t i = 0; i < c.lights.size(); ++i)
        pdf += c.probability[i] * this->pdf(c.lights[i], t.sampler, x, n, w);
    counters.pdf_evaluations += c.lights.size();
    return pdf;
}

MisEstimator& PointLighting::Impl::estimator(std::unordered_map<std::uint64_t, MisEstimator>& cache,
                                             std::uint64_t key, const std::vector<int>& active,
                                             const int* counts, bool fresh) {
    auto it = cache.find(key);
    // Counts other than the settings' (a final partial pass, an allocated
    // tile's): kept while the next point asks for the same.
    auto same_counts = [&](const MisEstimator& e) {
        for (std::size_t a = 0; a < active.size(); ++a)
            if (e.counts()[a] != counts[active[a]]) return false;
        return true;
    };
    if (it != cache.end() && fresh && !same_counts(it->second)) {
        cache.erase(it);
        it = cache.end();
    }
    if (it == cache.end()) {
        std::vector<int> n;
        for (int k : active) n.push_back(counts[k]);
        StrategyOptions options = p_.settings.options;
        options.sequence_rounds = true;  // each technique draws one scrambled sequence
        // One technique: every weighting is 1 and the optimal α is the mean
        // itself, so each strategy's estimate is the plain mean of f/p, which
        // the balance heuristic forms without the optimal moments and solve
        // (~5 % of a one-round pass on the race's one-technique scenes).
        const Strategy strategy = active.size() == 1 ? Strategy::Balance : p_.settings.strategy;
        it = cache.emplace(key, MisEstimator(strategy, int(active.size()), 3, n, options))
                 .first;
    }
    it->second.reset();
    return it->second;
}

void PointLighting::Impl::choose_active(std::uint64_t point, Probes& probes,
                                        const Footprint* footprint, Active& active) {
    // Light choice (which lights, with what probability) is made once per
    // point and kept for every sample of the footprint: per-point tables over
    // the centre and corners together (choose_lights_over); selectors at the
    // centre — or, where no light applies there, at the first corner where
    // one does. A fixed choice is a valid technique at every position:
    // its density at a sample's own position x_s is Σ_l P(l) p_l(ω | x_s),
    // which is what technique_pdf evaluates, so the combination stays
    // unbiased; a light that applies nowhere it was probed is left to the
    // other techniques there.
    const int n_probes = probes.count();
    // Anchored weights serve only per-point tables by unoccluded irradiance;
    // an anchor costs a slot per integrated light (16k on an emissive mesh).
    bool irradiance_tables = false;
    for (int k : p_.techniques) {
        const Technique& t = p_.settings.techniques[k];
        irradiance_tables = irradiance_tables ||
                            (!t.bsdf && !p_.selector(t.selection) &&
                             (t.selection == LightSelection::Unoccluded ||
                              t.selection == LightSelection::Defensive));
    }
    set_anchor(irradiance_tables ? footprint : nullptr);
    if (p_.settings.shadowed_draws > 1) active.draws_per_count = draws_per_count_at(point, probes[0]);
    for (int k : p_.techniques) {
        const Technique& t = p_.settings.techniques[k];
        if (!t.bsdf) {
            bool reaches = false;
            if (footprint && !p_.selector(t.selection)) {
                std::uint8_t* kept = p_.table_reach.of(point);
                reaches = choose_lights_over(k, probes, kept ? kept + kept_reach_at_[k] : nullptr);
            } else {
                for (int i = 0; i < n_probes && !reaches; ++i)
                    reaches = choose_lights(k, probes[i].x, probes[i].n);
            }
            if (!reaches) continue;
            active.lights.push_back(k);
            active.light_mask |= std::uint64_t(1) << k;
        }
        active.all.push_back(k);
        active.mask |= std::uint64_t(1) << k;
    }
}

// The verdict is kept in the context's shadow_verdicts (a byte a texel) where
// the job keeps them, else probed again: the probe is deterministic. (A
// TexelTables entry per texel for it cost more: 128², 8 spp, CPU: area
// 1.3-1.5x with no texel shadowed, demo_room 1.65x.)
int PointLighting::Impl::draws_per_count_at(std::uint64_t point, const SurfacePoint& centre) {
    std::uint8_t* kept = point < p_.shadow_verdicts.size() ? &p_.shadow_verdicts[point] : nullptr;
    if (kept && *kept) return *kept;
    const int m = centre_in_shadow(centre) ? p_.settings.shadowed_draws : 1;
    if (kept) *kept = std::uint8_t(m);
    return m;
}

// Whether the integrated lights whose middle point (an area draw at u = ½, ½:
// the middle of the shape, or of the part a spread lets reach p) p does not
// see carry at least kShadowedShare of the light those middle points bring
// unoccluded, each weighed by its draw's f / pdf (a one-point estimate of the
// light's unoccluded irradiance at p); true too where no light's middle
// brings any. Deterministic, so a draw count chosen by it is fixed per texel
// before any of its samples. Not only where every middle is hidden: in
// shared_image the box hides the square light's middle from 15 % of the
// texels, where the sphere light alone would have kept them at one draw a
// count; the square's penumbra there (2 % of the texels, 5–20 % of the mean)
// held 56 % of the relMSE (bench/results/error_sources.txt).
// By area and that light alone, not by solid angle and every light along the
// direction: the spherical rectangle's construction and the emitter query
// cost ~3.3k instructions of a probe's ~4.3k a light on the race's rect
// lights (callgrind, 128² demo_room: the probe took 1.5 samples' work a
// texel, ~28 % of a 3-spp bake). The brightest middle is traced first and
// the rays stop once the verdict is settled (one ray where that light alone
// carries more than the share and is seen).
bool PointLighting::Impl::centre_in_shadow(const SurfacePoint& p) {
    std::vector<MiddlePoint>& middles = middles_scratch_;
    middles.clear();
    double total = 0;
    for (std::uint32_t l : p_.integrated) {
        const auto s =
            sample_light(p_.scene.lights()[l], ShapeSampler::Area, p.x, p.n, 0.5, 0.5);
        if (!s || !(s->pdf > 0)) continue;
        const auto u = light_unoccluded(l, p.x, p.n, s->dir);
        if (!u) continue;
        const double weight = luminance(u->radiance) * u->cosine_factor / s->pdf;
        if (!(weight > 0)) continue;
        if (!p_.plan.shadow_rays) return false;  // nothing hides it: settled
        middles.push_back({weight, l, s->dir, u->distance});
        total += weight;
    }
    std::sort(middles.begin(), middles.end(),
              [](const MiddlePoint& a, const MiddlePoint& b) { return a.weight > b.weight; });
    double seen = 0, hidden = 0;
    for (const MiddlePoint& m : middles) {
        (light_occluded(m.light, p.x, p.ng, m.dir, m.distance) ? hidden : seen) += m.weight;
        if (hidden >= kShadowedShare * total) return true;
        if (seen > (1 - kShadowedShare) * total) return false;
    }
    return true;
}

// The ball about the centre through the footprint's farthest corner holds
// the whole footprint where it is flat (a parallelogram); a sample outside
// it (a footprint bent over a crease) is drawn for its own position.
// Only selectors draw with it: without them the corners are not made here.
void PointLighting::Impl::set_region(std::uint64_t point, Probes& probes) {
    const SurfacePoint& centre = probes[0];
    region_ = {centre.x, centre.n, 0.0};
    region_memo_.keep_in(p_.region_branching_of(point), p_.region_nodes);
    if (probes.count() == 1) return;
    double* kept = point < p_.region_radii.size() ? &p_.region_radii[point] : nullptr;
    if (kept && *kept >= 0) {
        region_.radius = *kept;
        return;
    }
    bool selectors = false;
    for (int k : p_.techniques)
        selectors = selectors || (!p_.settings.techniques[k].bsdf &&
                                  p_.selector(p_.settings.techniques[k].selection));
    if (!selectors) return;
    double r2 = 0;
    for (int j = 1; j < probes.count(); ++j) {
        const Vec3 d = probes[j].x - centre.x;
        r2 = std::max(r2, dot(d, d));
    }
    region_.radius = std::sqrt(r2);
    if (kept) *kept = region_.radius;
}

// Sampling and the densities at a sample both ask here with the sample's x,
// so both use the same rule there: the region's pmfs inside it, x's own
// outside. Either is a valid selection at x (light_selection.h).
LightSelector::Receiver PointLighting::Impl::receiver_at(const Vec3& x, const Vec3& n,
                                                         LightSelector::Memo*& memo) {
    const Vec3 d = x - region_.x;
    if (region_.radius > 0 && dot(d, d) <= region_.radius * region_.radius) {
        memo = &region_memo_;
        return region_;
    }
    memo = &memo_;
    return {x, n, 0.0};
}

void PointLighting::Impl::active_for(std::uint64_t stream, bool keep, const SurfacePoint& centre,
                                     const Footprint* footprint, Active& active) {
    Probes probes(centre, footprint);
    set_region(stream, probes);
    TexelTables& kept = p_.texel_tables;
    keep = keep && !cheap_tables_;
    if (keep)
        if (const TexelTables::Entry* entry = kept.find(stream)) {
            restore(*entry, active);
            if (p_.settings.shadowed_draws > 1)
                active.draws_per_count = draws_per_count_at(stream, centre);
            return;
        }
    ScopedTimer setup(keep && setup_timing_ && setup_timing_->on ? &setup_timing_->kept_setup
                                                                  : nullptr);
    choose_active(stream, probes, footprint, active);
    if (!keep) return;
    TexelTables::Entry entry;
    entry.mask = active.mask;
    entry.light_mask = active.light_mask;
    auto uses_table = [&](int k) { return !p_.selector(p_.settings.techniques[k].selection); };
    // One allocation of the exact size (no regrowth; bytes_of counts capacity).
    entry.tables.reserve(std::size_t(
        std::count_if(active.lights.begin(), active.lights.end(), uses_table)));
    for (int k : active.lights)
        if (uses_table(k))
            entry.tables.push_back({k, choices_[k].lights, choices_[k].probability});
    // Without a table, only where the point has a slot of its own (a bake's
    // texels: the slot's bytes are spent anyway): choosing the techniques
    // again — a tree's bounds at the centre, the point's probes — was ~12 % of
    // what a later pass repeated on the race's emissive_mesh (callgrind, 64²).
    // In the map, an entry for every texel of a large map would spend the
    // budget on them.
    if (entry.tables.empty() && !kept.has_slot(stream)) {
        setup.discard();  // nothing kept: not the kept tables' set-up
        return;
    }
    kept.keep(stream, std::move(entry));
}

// choose_active's result from a kept entry: the same techniques in the same
// order, and each table with the CDF choose_lights(_over) sums from it.
void PointLighting::Impl::restore(const TexelTables::Entry& kept, Active& active) {
    active.mask = kept.mask;
    active.light_mask = kept.light_mask;
    for (int k : p_.techniques) {
        const std::uint64_t bit = std::uint64_t(1) << k;
        if (kept.mask & bit) active.all.push_back(k);
        if (kept.light_mask & bit) active.lights.push_back(k);
    }
    for (const TexelTables::Table& t : kept.tables) {
        LightChoice& c = choices_[t.technique];
        c.lights = t.lights;
        c.probability = t.probability;
        c.cdf.clear();
        double running = 0;
        for (double w : c.probability) c.cdf.push_back(running += w);
        c.cdf.back() = 1.0;
    }
}

// Delta lights are not integrated: one shadow ray each when they are few; when
// they are many (plan.sample_delta_lights), their sum is estimated by drawing
// delta_samples lights from the light tree, u rotated over [0, 1) for each,
// weighted by 1/pmf — unbiased, as Cycles does.
Vec3 PointLighting::Impl::delta_lighting(const SurfacePoint& p, double u) {
    auto contribution = [&](std::uint32_t l) {
        const Light& light = p_.scene.lights()[l];
        const auto d = delta_illumination(light, p.x, p.n);
        if (!d) return Vec3();
        if (light.cast_shadow && p_.plan.shadow_rays) {
            ++counters.rays;
            if (p_.scene.geometry().occluded(offset_ray_origin(p.x, p.ng, d->direction),
                                             d->direction, 0, d->distance))
                return Vec3();
        }
        // E/π for Lambert; other receivers scale it by their closure's ratio.
        return d->irradiance *
               (kInvPi * p_.settings.receiver.lambert_ratio(dot(p.n, d->direction)));
    };
    Vec3 total;
    if (!p_.plan.sample_delta_lights) {
        for (std::uint32_t l : p_.delta) total += contribution(l);
        return total;
    }
    const int draws = p_.plan.delta_samples;
    for (int j = 0; j < draws; ++j) {
        const double uj = u + double(j) / draws;
        const auto pick =
            p_.delta_selector->sample(p.x, p.n, uj - std::floor(uj), &delta_memo_);
        if (pick) total += contribution(pick->light) / pick->pmf;
    }
    return total / double(draws);
}

void PointLighting::Impl::take_sample(const Active& active, std::size_t a,
                                      const ScrambledSobol& sequence, std::uint32_t index,
                                      const SurfacePoint& centre, const Footprint* footprint,
                                      const Estimators* into, int n_into,
                                      const TableDraw& drawn, const SelectorDraw* selected) {
    ++counters.samples;
    // Cancellation within a point (huge counts): see keep_going.
    if (p_.keep_going && counters.samples % 256 == 0 && !p_.keep_going())
        throw LightingCancelled{};
    // Dimension groups of the sequence: 0 footprint position, 1 the light
    // selection's bits below group 2's (a selector draws with the first
    // coordinate of group 2: draw_selector), 2 light shape or BSDF direction
    // (a light drawn from a per-point table takes its footprint position and
    // shape from its own sequence: `drawn`).
    const int k = active.all[a];
    const Technique& t = p_.settings.techniques[k];
    // The sample's position: the centre, the selector draw's, or one drawn
    // here (referred to, not copied: two copies were ~35 instructions).
    SurfacePoint drawn_at;
    const SurfacePoint* at = &centre;
    if (footprint) {
        if (selected) {
            at = &selected->p;
        } else {
            double fu = drawn.fu, fv = drawn.fv;
            if (t.bsdf) sequence.get_2d(index, 0, fu, fv);
            drawn_at = footprint->at(fu, fv);
            at = &drawn_at;
        }
        ++point_serial_;  // the solid-angle cache holds one position's shapes
    }
    const SurfacePoint& p = *at;
    const int hidden_index =
        into[0].hidden && in_hidden_part(k)
            ? int(std::find(active.hidden.begin(), active.hidden.end(), k) - active.hidden.begin())
            : -1;
    double u1 = drawn.u1, u2 = drawn.u2;  // a table draw brings its light's own
    if (t.bsdf) sequence.get_2d(index, 2, u1, u2);
    Vec3 w;
    bool ok;
    // The point's only technique draws lights: no weights to form, so a
    // sample may estimate its own light's part, f_l / (P(l) p_l(ω)), which
    // sums over lights to the whole integral. It needs neither the other
    // lights along ω (their densities and radiance: an all-hits query, a tree
    // walk each) nor a closest hit, only an occlusion ray up to the light.
    std::optional<SelectedLight> light;
    // A light sample's: its light's share of the technique's density, and
    // the distance to the point drawn on it.
    double own_density = 0, drawn_distance = 0;
    const bool own_light_only =
        own_light_estimates_ && active.all.size() == 1 && !t.bsdf && !pilot_;
    drawn_selection_ = {};  // none but this sample's own
    if (t.bsdf) {
        w = Frame(p.n).to_world(sample_cosine_hemisphere(u1, u2));
        ok = dot(w, p.n) > 0;
    } else {
        if (drawn.slot >= 0) {
            const LightChoice& c = choices_[k];
            light = SelectedLight{c.lights[drawn.slot], c.probability[drawn.slot]};
        } else {
            light = selected->light;
            u1 = selected->u1;
            u2 = selected->u2;
            if (light) drawn_selection_ = {selected->selector, light->light, light->pmf};
        }
        const auto s = light ? sample(light->light, t.sampler, p.x, p.n, u1, u2) : std::nullopt;
        ok = s && s->pdf > 0 && std::isfinite(s->pdf) && isfinite(s->dir);
        if (ok) w = s->dir;
        if (ok) own_density = light->pmf * s->pdf, drawn_distance = s->dist;
        if (ok && own_light_only) {
            const double pdf = light->pmf * s->pdf;
            ok = pdf > 0 && std::isfinite(pdf);
            if (ok) {
                const Integrand f = light_integrand(light->light, p.x, p.n, p.ng, w);
                const double main_f[3] = {f.main.x, f.main.y, f.main.z};
                const double hidden_f[3] = {f.hidden.x, f.hidden.y, f.hidden.z};
                for (int e = 0; e < n_into; ++e) {
                    into[e].main->add_sample(0, &pdf, main_f);
                    if (hidden_index >= 0) into[e].hidden->add_sample(0, &pdf, hidden_f);
                }
                return;
            }
        }
    }
    // Every technique's density at the sample's own position: the position
    // density is the same for all of them, so the MIS weights are those of
    // p_k(ω | x).
    const bool split = split_parts(active);
    if (split && t.bsdf && !p_.plan.world_occluders.empty())
        return take_occluder_sample(active, p, sequence.get_1d(index, 1), u1, u2, w, ok,
                                    hidden_index, into, n_into);
    if (split && t.bsdf) return take_world_sample(active, p, w, ok, hidden_index, into, n_into);
    // The sample's technique in the main estimator (split: the light techniques').
    const int main_index =
        split ? int(std::find(active.lights.begin(), active.lights.end(), k) - active.lights.begin())
              : int(a);
    const std::size_t main_size = main_techniques(active).size();
    double pdfs[kMaxMisTechniques], hidden_pdfs[kMaxMisTechniques], main_pdfs[kMaxMisTechniques];
    std::optional<Integrand> light_f;
    if (ok && light && clip_at_blocker_) {
        light_f = integrand_to_blocker(p.x, p.n, p.ng, w, light->light, drawn_distance);
        if (add_unlit_sample(main_size, main_index, hidden_index, own_density, *light_f, into,
                             n_into))
            return;
    } else if (ok && t.bsdf && bsdf_to_blocker_) {
        light_f = integrand_to_blocker(p.x, p.n, p.ng, w, ~0u, 0);
    }
    if (ok) {
        for (std::size_t b = 0; b < active.all.size(); ++b) {
            pdfs[b] = technique_pdf(active.all[b], p.x, p.n, w);
            // A light seen edge-on from x_s (a measure-zero configuration)
            // can give a non-finite density: it cannot produce ω there.
            if (!std::isfinite(pdfs[b])) pdfs[b] = 0;
        }
        ok = pdfs[a] > 0;
    }
    if (!ok) {
        if (pilot_) pilot_->add_work(k, 1.0);
        for (int e = 0; e < n_into; ++e) {
            into[e].main->add_null_sample(main_index);
            if (hidden_index >= 0) into[e].hidden->add_null_sample(hidden_index);
        }
        return;
    }
    const std::uint64_t rays_before = counters.rays;
    const Integrand f = light_f ? *light_f : integrand(p.x, p.n, p.ng, w);
    if (pilot_) record_sample(active, a, pdfs, f.main + f.hidden, rays_before);
    const double main_f[3] = {f.main.x, f.main.y, f.main.z};
    const double hidden_f[3] = {f.hidden.x, f.hidden.y, f.hidden.z};
    std::size_t h = 0;
    if (hidden_index >= 0)
        for (std::size_t b = 0; b < active.all.size(); ++b)
            if (in_hidden_part(active.all[b])) hidden_pdfs[h++] = pdfs[b];
    const double* own_pdfs = pdfs;
    if (split) {
        std::size_t m = 0;
        for (std::size_t b = 0; b < active.all.size(); ++b)
            if (!p_.settings.techniques[active.all[b]].bsdf) main_pdfs[m++] = pdfs[b];
        own_pdfs = main_pdfs;
    }
    for (int e = 0; e < n_into; ++e) {
        into[e].main->add_sample(main_index, own_pdfs, main_f);
        if (hidden_index >= 0) into[e].hidden->add_sample(hidden_index, hidden_pdfs, hidden_f);
    }
}

// split_parts' cosine draw: the world's part alone, seen through emitters
// (split_world) — one closest hit, no densities but its own (every
// technique of the hidden part is a `bsdf`, of one density).
void PointLighting::Impl::take_world_sample(const Active& active, const SurfacePoint& p,
                                            const Vec3& w, bool ok, int hidden_index,
                                            const Estimators* into, int n_into) {
    const double cos_theta = ok ? dot(p.n, w) : 0;
    if (!(cos_theta > 0) || hidden_index < 0) {
        for (int e = 0; e < n_into; ++e)
            if (hidden_index >= 0) into[e].hidden->add_null_sample(hidden_index);
        return;
    }
    const GeometryScene& geometry = p_.scene.geometry();
    ++counters.rays;
    const std::optional<RayHit> blocker = geometry.closest_hit(
        offset_ray_origin(p.x, p.ng, w), w, 0, std::numeric_limits<double>::infinity());
    Integrand f;
    split_world(f, p.x, w, blocker);
    const Vec3 world = f.hidden * receiver_cosine_factor(p_.settings.receiver, cos_theta);
    const double world_f[3] = {world.x, world.y, world.z};
    double pdfs[kMaxMisTechniques];
    std::fill(pdfs, pdfs + active.hidden.size(), cos_theta * kInvPi);
    for (int e = 0; e < n_into; ++e) into[e].hidden->add_sample(hidden_index, pdfs, world_f);
}

// The world's part is L_w (A − B): A = ∫_H c(ω) dω over the hemisphere,
// c the receiver's closure (receiver_cosine_factor: cos⁺/π for Lambert,
// Receiver::hemisphere_integral), B = ∫ c(ω) [the first hit along ω does not
// emit] dω. A direction whose first hit is on mesh m lies in the outline of
// m's bounding box, which from x outside the box is the union of the box
// faces turned toward x (disjoint). A face F drawn with probability W_F/W
// (W_F a positive weight, W their sum) and ω toward a point uniform on its
// area A_F (density d²/(A_F cos_F) in solid angle, d the point's distance):
//     B̂ = c(ω) (A_F cos_F / d²) W / W_F [the first hit along ω is on F's mesh],
// E[B̂] = Σ_F ∫_F c(ω)[first hit on mesh(F)] dω = B: each hidden direction
// counts once, through its own mesh's box. Unbiased; the sample enters the
// world's estimator as L_w (A − B̂) with density 1 (its only technique).
// Where x lies in a box that is not flat (its mesh may surround x) or the
// shading normal is not the geometric one (the receiver itself may then hide
// directions above n's horizon): the cosine draw w, as take_world_sample. A
// flat box holding x is a plane through x: hit at grazing only (measure
// zero), left out.
void PointLighting::Impl::take_occluder_sample(const Active& active, const SurfacePoint& p,
                                               double u_face, double u1, double u2,
                                               const Vec3& w, bool ok, int hidden_index,
                                               const Estimators* into, int n_into) {
    if (hidden_index < 0 || dot(p.n, p.ng) < 1 - 1e-9)
        return take_world_sample(active, p, w, ok, hidden_index, into, n_into);
    constexpr int kMaxFaces = 3 * kFewWorldOccluders;
    struct Face {
        Vec3 corner, edge_u, edge_v;
        std::uint32_t mesh;
    } faces[kMaxFaces];
    double weight[kMaxFaces];
    int count = 0;
    double total = 0;
    const double x[3] = {p.x.x, p.x.y, p.x.z};
    for (const EffectPlan::OccluderBox& box : p_.plan.world_occluders) {
        const double lo[3] = {box.lo.x, box.lo.y, box.lo.z}, hi[3] = {box.hi.x, box.hi.y, box.hi.z};
        bool inside = true, flat = false;
        for (int a = 0; a < 3; ++a) {
            inside = inside && lo[a] <= x[a] && x[a] <= hi[a];
            flat = flat || lo[a] == hi[a];
        }
        if (inside && flat) continue;
        if (inside) return take_world_sample(active, p, w, ok, hidden_index, into, n_into);
        for (int a = 0; a < 3; ++a) {
            if (lo[a] <= x[a] && x[a] <= hi[a]) continue;  // neither face of axis a faces x
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            if (lo[b] == hi[b] || lo[c] == hi[c]) continue;  // a face of no area
            double corner[3] = {lo[0], lo[1], lo[2]}, eu[3] = {}, ev[3] = {};
            corner[a] = x[a] < lo[a] ? lo[a] : hi[a];
            eu[b] = hi[b] - lo[b];
            ev[c] = hi[c] - lo[c];
            Face& f = faces[count];
            f = {Vec3(corner[0], corner[1], corner[2]), Vec3(eu[0], eu[1], eu[2]),
                 Vec3(ev[0], ev[1], ev[2]), box.mesh};
            // The face's solid angle about its centre (area · cos / d²): any
            // positive weight keeps B̂ unbiased; this one needs no trigonometry.
            const Vec3 d = f.corner + 0.5 * (f.edge_u + f.edge_v) - p.x;
            const double d2 = dot(d, d);
            weight[count] = eu[b] * ev[c] * std::abs(x[a] - corner[a]) / (d2 * std::sqrt(d2));
            if (!(weight[count] > 0) || !std::isfinite(weight[count])) continue;
            total += weight[count++];
        }
    }
    double hidden = 0;
    if (count > 0) {
        double pick = u_face * total;
        int f = 0;
        while (f + 1 < count && pick >= weight[f]) pick -= weight[f++];
        // A point uniform on the face's area: density d²/(A cos_F) in solid
        // angle. Against a spherical rectangle (uniform in solid angle) on
        // emission_world: 1–5 % more error per sample, 1.4× cheaper a round
        // (bench/results/error_sources.txt, 2026-12-01).
        const Face& face = faces[f];
        const Vec3 to = face.corner + u1 * face.edge_u + u2 * face.edge_v - p.x;
        const double d2 = dot(to, to);
        const Vec3 dir = to / std::sqrt(d2);
        const double cos_theta = dot(p.n, dir);
        const double cos_face = std::abs(dot(dir, normalize(cross(face.edge_u, face.edge_v))));
        if (cos_theta > 0 && cos_face > 0 && d2 > 0) {
            ++counters.rays;
            const std::optional<RayHit> blocker = p_.scene.geometry().closest_hit(
                offset_ray_origin(p.x, p.ng, dir), dir, 0, std::numeric_limits<double>::infinity());
            if (blocker && blocker->mesh == face.mesh)
                hidden = receiver_cosine_factor(p_.settings.receiver, cos_theta) *
                         length(cross(face.edge_u, face.edge_v)) * cos_face / d2 * total /
                         weight[f];
        }
    }
    const auto e = emitted_radiance(p_.scene.lights()[world_through_], p.x, p.n);
    const Vec3 world =
        e ? e->radiance * (p_.settings.receiver.hemisphere_integral() - hidden) : Vec3();
    const double world_f[3] = {world.x, world.y, world.z};
    double pdfs[kMaxMisTechniques];
    std::fill(pdfs, pdfs + active.hidden.size(), 1.0);
    for (int e2 = 0; e2 < n_into; ++e2) into[e2].hidden->add_sample(hidden_index, pdfs, world_f);
}

// A sample whose integrand is 0 (its light hidden by a surface that does not
// emit, so that nothing along it is seen) adds 0 to every sum of the estimators,
// whatever the densities, except the optimal strategies' moments among
// several techniques (and the pilot's records). There it goes in with its
// own technique's density bounded below by its light's share (> 0) and the
// others' left at 0 — no emitter query, no tree walks.
bool PointLighting::Impl::add_unlit_sample(std::size_t main_size, int main_index,
                                           int hidden_index, double own_density,
                                           const Integrand& f, const Estimators* into,
                                           int n_into) {
    const bool zero = f.main.x == 0 && f.main.y == 0 && f.main.z == 0 && f.hidden.x == 0 &&
                      f.hidden.y == 0 && f.hidden.z == 0;
    const bool densities_unused =
        !pilot_ && (main_size == 1 || !is_optimal(p_.settings.strategy));
    if (!zero || !densities_unused || !(own_density > 0) || !std::isfinite(own_density))
        return false;
    double pdfs[kMaxMisTechniques] = {}, hidden_pdfs[kMaxMisTechniques] = {};
    pdfs[main_index] = own_density;
    if (hidden_index >= 0) hidden_pdfs[hidden_index] = own_density;
    const double none[3] = {0, 0, 0};
    for (int e = 0; e < n_into; ++e) {
        into[e].main->add_sample(main_index, pdfs, none);
        if (hidden_index >= 0) into[e].hidden->add_sample(hidden_index, hidden_pdfs, none);
    }
    return true;
}

// One sample for the allocation pilot, over the settings' techniques (those
// not active here have density 0 at it). Its work: one unit for the draw, the
// densities and the integrand, and one per ray traced — a shadow ray costs
// about as much as the rest of a sample, and rays are what the techniques'
// samples differ in (a BSDF direction that meets no light traces none).
void PointLighting::Impl::record_sample(const Active& active, std::size_t a, const double* pdfs,
                                        const Vec3& f, std::uint64_t rays_before) {
    double all[kMaxMisTechniques] = {};
    for (std::size_t b = 0; b < active.all.size(); ++b) all[active.all[b]] = pdfs[b];
    const double y = luminance(f);
    pilot_->add_sample(all, &y);
    pilot_->add_work(active.all[a], 1.0 + double(counters.rays - rays_before));
}

void PointLighting::Impl::set_draw_starts(int first_round,
                                          const std::vector<DrawnRounds>* earlier) {
    const int K = p_.settings.streams;
    const std::vector<int>& samples = p_.settings.samples;
    draw_start_.assign(samples.size() * K, 0);
    if (!earlier) {
        for (std::size_t k = 0; k < samples.size(); ++k)
            for (int s = 0; s < K; ++s)
                draw_start_[k * K + s] = std::uint32_t(rounds_in_stream(s, first_round, K) * samples[k]);
        return;
    }
    int next = 0;
    for (const DrawnRounds& d : *earlier) {
        if (d.first_round != next || d.rounds < 0)
            throw std::invalid_argument("earlier: calls must follow each other from round 0");
        const int* counts = d.counts ? d.counts : samples.data();
        for (std::size_t k = 0; k < samples.size(); ++k)
            for (int s = 0; s < K; ++s)
                draw_start_[k * K + s] += std::uint32_t(
                    counts[k] * (rounds_in_stream(s, d.first_round + d.rounds, K) -
                                 rounds_in_stream(s, d.first_round, K)));
        next += d.rounds;
    }
    if (next != first_round)
        throw std::invalid_argument("earlier: rounds add up to " + std::to_string(next) +
                                    ", not first_round " + std::to_string(first_round));
}

Vec3 PointLighting::Impl::balance_of(const Estimators& e) {
    Vec3 total;
    for (const MisEstimator* m : {e.main, e.hidden}) {
        if (!m) continue;
        double b[3];
        m->balance_estimates(b);
        total += Vec3(b[0], b[1], b[2]);
    }
    return total;
}

void PointLighting::Impl::set_streams(const Estimators& all, int count) {
    all.main->set_streams(count);
    if (all.hidden) all.hidden->set_streams(count);
}

void PointLighting::Impl::set_stream(const Estimators& all, int s) {
    all.main->set_stream(s);
    if (all.hidden) all.hidden->set_stream(s);
}

// With a low-discrepancy sequence the balance heuristic can converge faster
// than the optimal weights' control variate, whose α is estimated from the
// same few samples (issue 10: optimal MIS must never lose). The K streams are
// independent randomizations, so the spread of their estimates measures each
// estimator's actual error; the point keeps whichever spreads less (luminance,
// weighted by the streams' rounds). A selection from 4 streams is noisy, but
// it picks between two unbiased-or-consistent estimates of the same value.
bool PointLighting::Impl::balance_is_better(const Vec3* optimal, const Vec3* balance,
                                            const int* stream_rounds) {
    double rounds = 0, mean_o = 0, mean_b = 0;
    double opt[kMaxSampleStreams], bal[kMaxSampleStreams];
    for (int s = 0; s < kMaxSampleStreams; ++s) {
        if (!stream_rounds[s]) continue;
        opt[s] = luminance(optimal[s]);
        bal[s] = luminance(balance[s]);
        rounds += stream_rounds[s];
        mean_o += opt[s] * stream_rounds[s];
        mean_b += bal[s] * stream_rounds[s];
    }
    mean_o /= rounds;
    mean_b /= rounds;
    double spread_o = 0, spread_b = 0;
    for (int s = 0; s < kMaxSampleStreams; ++s) {
        if (!stream_rounds[s]) continue;
        spread_o += stream_rounds[s] * (opt[s] - mean_o) * (opt[s] - mean_o);
        spread_b += stream_rounds[s] * (bal[s] - mean_b) * (bal[s] - mean_b);
    }
    return spread_b < spread_o;
}

Vec3 PointLighting::Impl::estimate_of(const Estimators& e, Vec3* variance) {
    Vec3 total;
    const MisEstimator* estimators[2] = {e.main, e.hidden};
    for (int i = 0; i < 2; ++i) {
        if (!estimators[i]) continue;
        MisResult& r = results_[i];
        estimators[i]->result(r);
        total += Vec3(r.estimate[0], r.estimate[1], r.estimate[2]);
        if (variance) *variance += Vec3(r.variance[0], r.variance[1], r.variance[2]);
    }
    return total;
}

// optimal-direct's stream s is corrected with the α solved from the other
// streams (cross-fitting by stream): the streams' spread then holds the
// fit's error too, which one α common to all of them hides (issue 10).
void PointLighting::Impl::stream_of(const Estimators& whole, int s, bool cross_fit,
                                    Vec3& balance, Vec3& corrected) const {
    balance = corrected = Vec3();
    const MisEstimator* estimators[2] = {whole.main, whole.hidden};
    for (int i = 0; i < 2; ++i) {
        if (!estimators[i]) continue;
        double b[3], e[3];
        if (cross_fit)
            estimators[i]->stream_cross_fit(s, b, e);
        else
            estimators[i]->stream_estimates(s, nullptr, b);
        balance += Vec3(b[0], b[1], b[2]);
        corrected += cross_fit ? Vec3(e[0], e[1], e[2]) : Vec3(b[0], b[1], b[2]);
    }
}

// Per-light sample streams for the light techniques that draw from a
// per-point table: the table picks a light by the technique sequence's
// selection dimension, and the light's shape point is the next unused point
// of that light's OWN scrambled sequence (per technique, stream and light).
// Each light's draws then form a stratified prefix whatever its share — a
// strip of one shared net is stratified only for dyadic shares, and a shape
// taken from an unrelated dimension not at all. The draw's footprint
// position comes from the same point of that sequence: one 4-D Sobol' point
// (ScrambledSobol::get_4d), the shape from dimensions 0–1 (a (0,2)-net), the
// position from 2–3, all four a (3,m,4)-net, so a light's draws are
// stratified in position and light point together. That matters in a
// penumbra, where visibility depends on both. On a penumbra texel lit by two
// lights (tests/core/test_footprint_strata.cpp), the variance at 256 samples
// over one sample's: positions from the technique's sequence 1/680; from the
// light's sequence as a second 2-D pair, shuffled apart (padding) 1/1400;
// the 4-D point 1/4860. On the demo room's 128² floor (4.7 cm texels),
// relMSE at 256 equal samples against Cycles' (3 seeds): 1.03 → 0.66, its
// penumbrae (edge texels) 0.97 → 0.57; shared_image (1.6 cm texels) 0.99 →
// 0.93 (issue 9; bench/results/error_sources.txt). Unbiased: a light's sequence
// is independent of the selections, so its next point is uniform whatever
// the count, in position as in shape. A later pass continues every count:
// the table is the same at every pass, so the counts are those the point's
// last call left (LightingContext::draw_counts, where kept), else the
// selections of earlier rounds are replayed (cheap per draw: no rays, one
// table lookup each; but every pass replays them all).
class PointLighting::Impl::LightStreams {
public:
    LightStreams(Impl& impl, std::uint64_t base, std::uint64_t point, const Active& active)
        : impl_(impl), base_(base), lights_(table_slots(impl)),
          streams_(impl.p_.settings.streams), taken_(impl.taken_scratch_),
          sequences_(impl.sequences_scratch_), kept_(impl.p_.draw_counts.of(point)),
          active_(active) {
        const auto& techniques = impl.p_.settings.techniques;
        // Counts only where a technique draws from a table: zeroing them per
        // point for 16k tree-drawn lights cost 40 % of an emissive mesh's bake.
        if (std::none_of(active.lights.begin(), active.lights.end(),
                         [&](int k) { return uses_table(k); }))
            return;
        taken_.assign(techniques.size() * std::size_t(streams_) * lights_, 0);
        forget_sequences(sequences_, taken_.size());
        for (int k : active.lights) {
            if (!uses_table(k)) continue;
            for (int s = 0; s < streams_; ++s) {
                const std::uint32_t start = impl.draw_start(k, s);
                if (start == 0) continue;  // a first pass: nothing to count
                const ScrambledSobol& seq = impl.technique_sequence(std::size_t(k), s);
                for (std::uint32_t i = restore(k, s, start); i < start; ++i)
                    ++count(k, s, slot(k, seq, i));
            }
        }
    }
    bool uses_table(int k) const {
        return impl_.kept_counts_at_[std::size_t(k)] != ~std::size_t(0);
    }
    // Leaves the counts for the point's next call (after all of this one's draws).
    void keep() const {
        if (!kept_) return;
        for (int k : active_.lights)
            if (uses_table(k))
                for (int s = 0; s < streams_; ++s) {
                    std::uint32_t* to = kept(k, s);
                    const std::size_t n = table_size(k);
                    for (std::size_t i = 0; i < n; ++i) to[i] = taken_[cell(k, s, int(i))];
                }
    }
    // Technique k's draw `index` of stream s: its light and shape point.
    TableDraw draw(int k, int s, const ScrambledSobol& seq, std::uint32_t index) {
        TableDraw d;
        d.slot = slot(k, seq, index);
        const std::size_t at = cell(k, s, d.slot);
        std::optional<ScrambledSobol>& light_sequence = sequences_[at];
        if (!light_sequence) {  // made at its light's first draw of the point
            const std::uint64_t id = (std::uint64_t(k) * streams_ + std::uint64_t(s)) << 32 |
                                     std::uint64_t(d.slot + 1);
            light_sequence.emplace(base_ ^ mix64(0x6a09e667f3bcc909ull ^ id));
        }
        double u[4];
        light_sequence->get_4d(taken_[at]++, 0, u);
        d.u1 = u[0];
        d.u2 = u[1];
        d.fu = u[2];
        d.fv = u[3];
        return d;
    }

private:
    // Technique k's kept counts of stream s (a slot per integrated light).
    std::uint32_t* kept(int k, int s) const {
        const std::size_t lights = impl_.p_.integrated.size();
        return kept_ + impl_.kept_counts_at_[std::size_t(k)] + std::size_t(s) * lights;
    }
    std::size_t table_size(int k) const {
        return std::min(impl_.choices_[k].lights.size(), impl_.p_.integrated.size());
    }
    // The kept counts of technique k's stream s, where they count no more
    // than the `start` draws before this call (then a prefix of them): how
    // many they count, from which the rest are counted. 0 where none are kept.
    std::uint32_t restore(int k, int s, std::uint32_t start) {
        if (!kept_) return 0;
        const std::uint32_t* from = kept(k, s);
        const std::size_t n = table_size(k);
        std::uint64_t counted = 0;
        for (std::size_t i = 0; i < n; ++i) counted += from[i];
        if (counted > start) return 0;  // ahead of this call (a probe's): count afresh
        for (std::size_t i = 0; i < n; ++i) count(k, s, int(i)) = from[i];
        return std::uint32_t(counted);
    }
    // The longest table's size, not the scene's light count: the counts are
    // cleared per point, and a scene of many emitter triangles (drawn through
    // the light tree, no table) would otherwise clear a vector that long at
    // every point and pass (16k triangles: ~0.4 s per pass at 128²).
    static std::size_t table_slots(const Impl& impl) {
        std::size_t n = 0;
        for (const LightChoice& c : impl.choices_) n = std::max(n, c.lights.size());
        return n;
    }
    int slot(int k, const ScrambledSobol& seq, std::uint32_t index) const {
        const LightChoice& c = impl_.choices_[k];
        const double u = seq.get_1d(index, 1);
        return int(std::min<std::size_t>(
            std::upper_bound(c.cdf.begin(), c.cdf.end(), u) - c.cdf.begin(), c.lights.size() - 1));
    }
    std::size_t cell(int k, int s, int slot) const {
        return (std::size_t(k) * streams_ + std::size_t(s)) * lights_ + std::size_t(slot);
    }
    std::uint32_t& count(int k, int s, int slot) { return taken_[cell(k, s, slot)]; }
    Impl& impl_;
    std::uint64_t base_;
    std::size_t lights_;
    int streams_;
    std::vector<std::uint32_t>& taken_;  // per technique, stream and table slot
    std::vector<std::optional<ScrambledSobol>>& sequences_;  // each slot's own, per cell
    std::uint32_t* kept_;  // the point's kept counts, or null
    const Active& active_;
};

// How a call's rounds fall into the streams, and whether each stream's
// estimate is kept: for the error when asked, and for the optimal strategies'
// choice against balance (balance_is_better).
PointLighting::Impl::RoundPlan PointLighting::Impl::plan_rounds(int first_round, int rounds,
                                                                bool want_error) const {
    RoundPlan plan;
    plan.rounds = rounds;
    const int streams = p_.settings.streams;
    for (int r = first_round; r < first_round + rounds; ++r) ++plan.stream_rounds[r % streams];
    plan.streams_used = int(std::count_if(plan.stream_rounds, plan.stream_rounds + streams,
                                          [](int m) { return m > 0; }));
    plan.by_stream = plan.streams_used >= 2 && (want_error || is_optimal(p_.settings.strategy));
    plan.in_whole = streams_in_whole(p_.settings.strategy, plan.by_stream);
    return plan;
}

void PointLighting::Impl::set_hidden_part(Active& active) const {
    active.hidden.clear();
    active.hidden_mask = 0;
    if (!p_.plan.bsdf_invisible_lights && world_through_ == ~0u) return;
    for (int k : active.all)
        if (in_hidden_part(k)) {
            active.hidden.push_back(k);
            active.hidden_mask |= std::uint64_t(1) << k;
        }
}

// Estimators: one over all rounds (with per-stream sums inside when
// plan.in_whole), else one more per stream that holds rounds.
void PointLighting::Impl::set_up_estimators(const Active& active, const RoundPlan& plan,
                                            const int* counts, bool fresh, Estimators& all,
                                            Estimators* per) {
    if (active.all.empty()) return;
    const std::uint64_t fresh_key = fresh ? std::uint64_t(1) << 50 : 0;  // uncached counts
    const bool hidden = !active.hidden.empty();
    const std::vector<int>& main = main_techniques(active);
    const std::uint64_t main_mask = split_parts(active) ? active.light_mask : active.mask;
    for (int s = -1; s < p_.settings.streams; ++s) {
        if (s >= 0 && (!plan.by_stream || plan.in_whole || plan.stream_rounds[s] == 0)) continue;
        const std::uint64_t key = fresh_key | (std::uint64_t(s + 1) << 40);
        Estimators& e = s < 0 ? all : per[s];
        if (s < 0) counters.systems += hidden ? 2 : 1;  // streams only measure the error
        e.main = &estimator(main_cache_, key | main_mask, main, counts, fresh);
        if (hidden)
            e.hidden = &estimator(hidden_cache_, key | active.hidden_mask, active.hidden, counts,
                                  fresh);
    }
    set_streams(all, plan.in_whole ? p_.settings.streams : 0);
}

// The point's estimate once its rounds are in: the whole's estimate, then
// each stream's — the optimal strategies compare it with balance's
// (balance_is_better), and the chosen one's spread is the error;
// optimal-direct's streams are cross-fitted (stream_of) and their mean is its
// estimate, so that spread is its error. own_variance: as for
// independent draws; error_variance: from the streams' spread when kept.
Vec3 PointLighting::Impl::point_estimate(const Active& active, const RoundPlan& plan,
                                         const Estimators& all, const Estimators* per,
                                         const DeltaSums& delta, Vec3& own_variance,
                                         Vec3& error_variance, StreamEstimates* streams) {
    constexpr int K = kMaxSampleStreams;  // streams past settings.streams hold no rounds
    const int rounds = plan.rounds;
    const bool sampled = !active.all.empty();
    const bool optimal = is_optimal(p_.settings.strategy);
    const bool direct = p_.settings.strategy == Strategy::OptimalDirect;
    own_variance = Vec3();
    Vec3 whole, total = delta.at_centre;
    if (sampled) whole = estimate_of(all, &own_variance);
    Vec3 stream_estimate[K], stream_balance[K];
    if (plan.by_stream && sampled)
        for (int s = 0; s < K; ++s) {
            if (!plan.stream_rounds[s]) continue;
            if (!plan.in_whole) {  // optimal-progressive: its own cross-fit per stream
                stream_balance[s] = balance_of(per[s]);
                stream_estimate[s] = estimate_of(per[s]);
                continue;
            }
            // The heuristics' own estimate; optimal-direct's cross-fitted.
            stream_of(all, s, direct, stream_balance[s], stream_estimate[s]);
        }
    const bool cross_fitted = sampled && direct && plan.in_whole;
    if (cross_fitted) {  // the streams' mean, unless negative where balance is not
        Vec3 mean;
        for (int s = 0; s < K; ++s)
            mean += stream_estimate[s] * (double(plan.stream_rounds[s]) / rounds);
        const Vec3 balance = balance_of(all);
        const bool negative = (mean.x < 0 && balance.x >= 0) || (mean.y < 0 && balance.y >= 0) ||
                              (mean.z < 0 && balance.z >= 0);
        whole = negative ? balance : mean;
        if (negative)
            for (int s = 0; s < K; ++s) stream_estimate[s] = stream_balance[s];
    }
    const bool use_balance =
        sampled && plan.by_stream && optimal &&
        balance_is_better(stream_estimate, stream_balance, plan.stream_rounds);
    if (sampled) total += use_balance ? balance_of(all) : whole;
    Vec3 delta_total;
    for (const Vec3& d : delta.sum) delta_total += d;
    total += delta_total / double(rounds);
    if (rounds > 1) {  // the delta lights' mean over positions, as independent draws
        const Vec3 m = delta_total / double(rounds);
        const Vec3 spread = delta.sum2 / double(rounds) - Vec3(m.x * m.x, m.y * m.y, m.z * m.z);
        own_variance += Vec3(std::max(0.0, spread.x), std::max(0.0, spread.y),
                             std::max(0.0, spread.z)) / double(rounds - 1);
    }
    error_variance = own_variance;
    if (!plan.by_stream) {
        if (streams && plan.streams_used == 1)  // the one stream's estimate is the point's
            for (int s = 0; s < K; ++s)
                if (plan.stream_rounds[s]) {
                    streams->rounds[s] = plan.stream_rounds[s];
                    streams->luminance[s] = luminance(total);
                }
        return total;
    }
    // Var(mean) = Σ m_s (e_s − ē)² / ((S − 1) M): the streams' estimates e_s
    // are independent with variance σ²/m_s.
    Vec3 e[K], mean;
    for (int s = 0; s < K; ++s) {
        if (!plan.stream_rounds[s]) continue;
        e[s] = delta.sum[s] / double(plan.stream_rounds[s]);
        if (sampled) e[s] += use_balance ? stream_balance[s] : stream_estimate[s];
        mean += e[s] * (double(plan.stream_rounds[s]) / rounds);
    }
    if (streams)
        for (int s = 0; s < K; ++s) {
            if (!plan.stream_rounds[s]) continue;
            streams->rounds[s] = plan.stream_rounds[s];
            streams->luminance[s] = luminance(e[s]);
        }
    error_variance = Vec3();
    for (int s = 0; s < K; ++s) {
        if (!plan.stream_rounds[s]) continue;
        const Vec3 d = e[s] - mean;
        error_variance += Vec3(d.x * d.x, d.y * d.y, d.z * d.z) * double(plan.stream_rounds[s]);
    }
    error_variance = error_variance / (double(plan.streams_used - 1) * rounds);
    return total;
}

void PointLighting::Impl::shade(std::uint64_t stream, int first_round, int rounds,
                                const SurfacePoint& centre, const Footprint* footprint,
                                const int* counts_in, double* value, double* variance,
                                double* own_variance_out, StreamEstimates* streams,
                                const std::vector<DrawnRounds>* earlier) {
    const int* counts = counts_in ? counts_in : p_.settings.samples.data();
    ++point_serial_;  // invalidates the per-point solid-angle cache
    Active& active = active_scratch_;
    active.clear();
    // Bakes shade a texel again at each pass (and a footprint's tables cost).
    active_for(stream, footprint || first_round > 0, centre, footprint, active);
    set_hidden_part(active);
    // A shadowed texel (shadowed_draws) draws m times every count, at every
    // pass: its draw indices are m times those of the counts.
    const int m = draws_per_count_ = active.draws_per_count;
    if (m > 1) {
        scaled_counts_.assign(counts, counts + p_.settings.samples.size());
        for (int& n : scaled_counts_) n *= m;
        counts = scaled_counts_.data();
    }

    // Round r belongs to stream r mod K; each (technique, stream) has its own
    // scrambled sequence, continued from round to round. Delta lights, when
    // positions vary, take one position per round from a sequence of their own.
    const int K = p_.settings.streams;
    const std::uint64_t base = mix64(p_.settings.seed ^ mix64(stream));
    const std::size_t delta_group = p_.settings.techniques.size();
    sequence_base_ = base;
    forget_sequences(technique_sequences_, (delta_group + 1) * std::size_t(K));
    set_draw_starts(first_round, earlier);
    if (m > 1)
        for (std::uint32_t& start : draw_start_) start *= std::uint32_t(m);
    LightStreams light_streams(*this, base, stream, active);
    const RoundPlan plan = plan_rounds(first_round, rounds, variance != nullptr);
    Estimators all{nullptr, nullptr}, per[kMaxSampleStreams] = {};
    set_up_estimators(active, plan, counts, counts_in != nullptr || m > 1, all, per);

    // Delta lights are evaluated once per round where positions vary or lights
    // are drawn, else once at the centre.
    DeltaSums delta;
    delta.per_round = !p_.delta.empty() && (footprint || p_.plan.sample_delta_lights);
    const bool by_stream_only = plan.by_stream && !plan.in_whole;
    ScopedTimer rounds_timer(setup_timing_ && setup_timing_->on ? &setup_timing_->rounds
                                                                 : nullptr);
    // Technique k's draw j of round r: its index in its stream's sequence.
    auto index_of = [&](int k, int r, int j) {
        const int s = r % K;
        return draw_start(k, s) +
               (std::uint32_t(r / K) - std::uint32_t(rounds_in_stream(s, first_round, K))) *
                   std::uint32_t(counts[k]) +
               std::uint32_t(j);
    };
    // Techniques whose lights come from a selector: each sample's light is
    // drawn into selector_draws_[now], and among many lights begun two
    // samples ahead and finished one ahead, in the slots after it
    // (SelectorDraw).
    auto draws_ahead = [&](int k) {
        return !p_.settings.techniques[k].bsdf && !light_streams.uses_table(k);
    };
    int now = 0;
    for (SelectorDraw& d : selector_draws_) d.k = -1;  // last call's: other sequences
    // Moves (r, a, j) to the sample after it in the loop's order; false past
    // the call's last.
    auto advance = [&](int& r, std::size_t& a, int& j) {
        ++j;
        while (j >= counts[active.all[a]]) {
            j = 0;
            if (++a == active.all.size()) {
                a = 0;
                if (++r == first_round + rounds) return false;
            }
        }
        return true;
    };
    // Finishes the light of the sample after (r, a, j) and begins the one
    // after that.
    auto draw_after = [&](int r, std::size_t a, int j) {
        if (!advance(r, a, j)) return;
        int k = active.all[a];
        if (draws_ahead(k)) {
            SelectorDraw& next = selector_draws_[(now + 1) % kSelectorDraws];
            const ScrambledSobol& seq = technique_sequence(std::size_t(k), r % K);
            const std::uint32_t index = index_of(k, r, j);
            if (next.is(k, seq, index)) finish_selector_draw(next);
            else draw_selector(k, seq, index, centre, footprint, next);
            if (next.light) prefetch_light(next.light->light);
        }
        if (!advance(r, a, j)) return;
        k = active.all[a];
        if (!draws_ahead(k)) return;
        begin_selector_draw(k, technique_sequence(std::size_t(k), r % K), index_of(k, r, j),
                            centre, footprint, selector_draws_[(now + 2) % kSelectorDraws]);
    };
    for (int r = first_round; r < first_round + rounds; ++r) {
        const int s = r % K;
        const std::uint32_t round_in_stream = std::uint32_t(r / K);
        if (delta.per_round) {
            const ScrambledSobol& seq = technique_sequence(delta_group, s);
            SurfacePoint at = centre;
            if (footprint) {
                double fu, fv;
                seq.get_2d(round_in_stream, 0, fu, fv);
                at = footprint->at(fu, fv);
            }
            const Vec3 d = delta_lighting(at, seq.get_1d(round_in_stream, 1));
            delta.sum[s] += d;
            delta.sum2 += Vec3(d.x * d.x, d.y * d.y, d.z * d.z);
        }
        const Estimators into[2] = {all, per[s]};
        if (plan.in_whole && !active.all.empty()) set_stream(all, s);
        for (std::size_t a = 0; a < active.all.size(); ++a) {
            const int k = active.all[a];
            const ScrambledSobol& seq = technique_sequence(std::size_t(k), s);
            const bool table = light_streams.uses_table(k);
            const bool from_selector = draws_ahead(k);
            for (int j = 0; j < counts[k]; ++j) {
                const std::uint32_t index = index_of(k, r, j);
                SelectorDraw* selected = nullptr;
                if (from_selector) {
                    selected = &selector_draws_[now];
                    if (!selected->is(k, seq, index))
                        draw_selector(k, seq, index, centre, footprint, *selected);
                    finish_selector_draw(*selected);  // (done a sample ahead)
                }
                if (draw_next_ahead_) draw_after(r, a, j);
                take_sample(active, a, seq, index, centre, footprint, into,
                            by_stream_only ? 2 : 1,
                            table ? light_streams.draw(k, s, seq, index) : TableDraw{}, selected);
                now = (now + 1) % kSelectorDraws;
            }
        }
    }
    rounds_timer.stop();
    light_streams.keep();
    if (!delta.per_round && !p_.delta.empty()) delta.at_centre = delta_lighting(centre, 0.0);

    Vec3 own_variance, error_variance;
    if (streams) *streams = StreamEstimates{};
    const Vec3 total =
        point_estimate(active, plan, all, per, delta, own_variance, error_variance, streams);
    for (int c = 0; c < 3; ++c) {
        value[c] = total[c];
        if (variance) variance[c] = error_variance[c];
        if (own_variance_out) own_variance_out[c] = own_variance[c];
    }
}

namespace {

void validate(const Scene& scene, const DirectLightingSettings& s) {
    if (!scene.committed())
        throw std::logic_error("scene: not committed (call commit before lighting)");
    if (s.techniques.size() != s.samples.size())
        throw std::invalid_argument("samples: expected one count per technique (" +
                                    std::to_string(s.techniques.size()) + "), got " +
                                    std::to_string(s.samples.size()));
    if (s.techniques.size() > kMaxMisTechniques)
        throw std::invalid_argument("techniques: at most " +
                                    std::to_string(kMaxMisTechniques));
    for (int n : s.samples)
        if (n < 0) throw std::invalid_argument("samples: counts must not be negative");
    if (s.rounds < 1) throw std::invalid_argument("rounds: must be at least 1");
    if (s.streams < 1 || s.streams > kMaxSampleStreams)
        throw std::invalid_argument("streams: must lie in [1, " +
                                    std::to_string(kMaxSampleStreams) + "], got " +
                                    std::to_string(s.streams));
    // Draw indices (round × count + j) and per-point totals are ints.
    long long per_point = 0;
    for (int n : s.samples) per_point += (long long)n * s.rounds;
    if (per_point > std::numeric_limits<int>::max())
        throw std::invalid_argument("samples: " + std::to_string(per_point) +
                                    " draws per point (counts × rounds) exceed the limit of " +
                                    std::to_string(std::numeric_limits<int>::max()));
    for (std::size_t i = 0; i < s.techniques.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (s.techniques[i] == s.techniques[j])
                throw std::invalid_argument("techniques: '" + s.techniques[i].name() +
                                            "' is listed twice");
}

}  // namespace

LightingContext::LightingContext(const Scene& scene_, const DirectLightingSettings& s)
    : scene((validate(scene_, s), scene_)),
      settings(s),
      plan(plan_effects(scene_, s.techniques, s.samples, s.points_on_mesh)),
      power(scene_.light_powers()) {
    for (std::size_t k = 0; k < settings.techniques.size(); ++k)
        if (plan.enabled[k]) techniques.push_back(int(k));
    for (std::uint32_t l = 0; l < scene.lights().size(); ++l) {
        const Light& light = scene.lights()[l];
        // A world left to `bsdf` is no light technique's to select.
        const bool bsdf_only = plan.world_by_bsdf && light.type == LightType::World;
        if (!bsdf_only) (light.is_delta() ? delta : integrated).push_back(l);
        if (scene.lights().size() <= kMaxTinyShapeTable)
            tiny_shapes.push_back(tiny_shape_of(light));
    }
    // Few lights: `uniform` and `power` keep their per-point tables over the
    // lights that reach x (no draw wasted on the others).
    const bool many = integrated.size() > std::size_t(kManyIntegratedLights);
    for (int k : techniques) {
        const Technique& t = settings.techniques[k];
        if (t.bsdf || (!many && t.selection != LightSelection::Tree)) continue;
        if (t.selection == LightSelection::Uniform && !uniform_selector)
            uniform_selector = &scene.light_selector(LightSelector::Kind::Uniform, false);
        if (t.selection == LightSelection::Power && !power_selector)
            power_selector = &scene.light_selector(LightSelector::Kind::Power, false);
        if (t.selection == LightSelection::Tree && !tree_selector)
            tree_selector = &scene.light_selector(LightSelector::Kind::Tree, false);
    }
    if (plan.sample_delta_lights)
        delta_selector = &scene.light_selector(LightSelector::Kind::Tree, true);
    keeps_texel_tables = std::any_of(
        settings.techniques.begin(), settings.techniques.end(), [](const Technique& t) {
            return !t.bsdf && t.selection != LightSelection::Uniform &&
                   t.selection != LightSelection::Power;
        });
}

void LightingContext::keep_shadow_verdicts(std::size_t points) {
    if (settings.shadowed_draws > 1 && settings.shadowed_draws <= 255)  // a byte each
        shadow_verdicts.assign(points, 0);
}

void LightingContext::keep_region_radii(std::size_t points) {
    // PointLighting's set_region makes a region only for selectors' draws.
    const bool selectors = std::any_of(techniques.begin(), techniques.end(), [&](int k) {
        return !settings.techniques[k].bsdf && selector(settings.techniques[k].selection);
    });
    if (selectors) region_radii.assign(points, -1.0);
}

namespace {

// The kept branching of the last context to end, for the next one to take.
// Its block (5.2 MB at 128²) was otherwise at times handed back to the system
// at a bake's end and faulted in anew by the next one: 16-20 ms of a 0.05 s
// budget in Blender, on emissive_mesh at 128² (bench/results/budgets.txt).
struct SpareBranching {
    std::mutex mutex;
    std::vector<LightSelector::KeptNode> nodes;
};
// Never destroyed: a context may end after static destruction has begun
// (a Python object freed at exit).
SpareBranching& spare_branching() {
    static SpareBranching* spare = new SpareBranching;
    return *spare;
}

}  // namespace

LightingContext::~LightingContext() {
    if (region_branching.capacity() == 0) return;
    SpareBranching& spare = spare_branching();
    std::lock_guard<std::mutex> lock(spare.mutex);
    if (region_branching.capacity() > spare.nodes.capacity()) spare.nodes.swap(region_branching);
}

void LightingContext::keep_region_branching(std::size_t points, std::size_t max_nodes) {
    // Only the tree's memo walks nodes (set_region's memo, for its draws).
    const bool tree = std::any_of(techniques.begin(), techniques.end(), [&](int k) {
        return !settings.techniques[k].bsdf &&
               settings.techniques[k].selection == LightSelection::Tree;
    });
    if (!tree || points == 0) return;
    region_nodes =
        std::min(max_nodes, kRegionBranchingBytes / sizeof(LightSelector::KeptNode) / points);
    if (region_nodes == 0) return;
    {
        SpareBranching& spare = spare_branching();
        std::lock_guard<std::mutex> lock(spare.mutex);
        if (spare.nodes.capacity() > region_branching.capacity()) region_branching.swap(spare.nodes);
    }
    region_branching.assign(points * region_nodes, {});
}

void LightingContext::keep_table_reach(std::size_t points) {
    if (keeps_texel_tables) return;  // their entries hold the tables
    std::size_t tables = 0;
    for (const Technique& t : settings.techniques) tables += !t.bsdf && !selector(t.selection);
    table_reach.index_points(points, tables * integrated.size());
}

void LightingContext::keep_draw_counts(std::size_t points) {
    std::size_t tables = 0;  // light techniques that draw from per-point tables
    for (const Technique& t : settings.techniques) tables += !t.bsdf && !selector(t.selection);
    draw_counts.index_points(points, tables * std::size_t(settings.streams) * integrated.size());
}

const LightSelector* LightingContext::selector(LightSelection selection) const {
    switch (selection) {
        case LightSelection::Uniform:
            return uniform_selector && !uniform_selector->empty() ? uniform_selector : nullptr;
        case LightSelection::Power:
            return power_selector && !power_selector->empty() ? power_selector : nullptr;
        case LightSelection::Tree: {
            static const LightSelector kNoLights;  // a tree technique never built: draws nothing
            return tree_selector ? tree_selector : &kNoLights;
        }
        case LightSelection::Unoccluded:
        case LightSelection::Defensive: return nullptr;
    }
    return nullptr;
}

PointLighting::PointLighting(const LightingContext& context)
    : impl_(std::make_unique<Impl>(context, counters)) {
    impl_->setup_timing_ = &setup_timing;
}
PointLighting::~PointLighting() = default;
PointLighting::PointLighting(PointLighting&& other) noexcept
    : counters(other.counters), setup_timing(other.setup_timing), impl_(std::move(other.impl_)) {
    if (impl_) impl_ = std::make_unique<Impl>(impl_->p_, counters);
    if (impl_) impl_->setup_timing_ = &setup_timing;
}

void PointLighting::shade(std::uint64_t stream, int first_round, int rounds,
                          const SurfacePoint& centre, const Footprint* footprint,
                          double value[3], double variance[3], const int* counts,
                          double own_variance[3], StreamEstimates* streams,
                          const std::vector<DrawnRounds>* earlier) {
    ScopedTimer timer(setup_timing.on ? &setup_timing.shading : nullptr);
    impl_->shade(stream, first_round, rounds, centre, footprint, counts, value, variance,
                 own_variance, streams, earlier);
}

int PointLighting::draws_per_count() const { return impl_->draws_per_count_; }

void PointLighting::record_into(AllocationPilot* pilot) {
    if (pilot && pilot->num_techniques() != int(impl_->p_.settings.techniques.size()))
        throw std::invalid_argument("pilot: expected one technique per settings technique");
    impl_->pilot_ = pilot;
}

void PointLighting::shade(std::uint64_t stream, int first_round, int rounds, const Vec3& x,
                          const Vec3& n, const Vec3& ng, double value[3],
                          double variance[3]) {
    impl_->shade(stream, first_round, rounds, SurfacePoint{x, n, ng}, nullptr, nullptr, value,
                 variance, nullptr, nullptr, nullptr);
}

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
    // Inside long points: report progress now and then (at most every 50 ms)
    // and stop once it asks to.
    std::atomic<double> last_report{0};
    auto seconds = [&] {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    context.keep_going = [&] {
        const double now = seconds();
        if (progress && now - last_report.load(std::memory_order_relaxed) >= 0.05) {
            std::unique_lock<std::mutex> lock(report, std::try_to_lock);
            last_report = now;
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
