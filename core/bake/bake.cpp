#include "bake/bake.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <sstream>
#include <limits>
#include <mutex>
#include <numeric>
#include <stdexcept>

#include "bake/dyadic_schedule.h"
#include "bake/uv_raster.h"
#include "bake/vertex_points.h"
#include "mis/allocation.h"
#include "render/progress_throttle.h"
#include "scene/surface_contacts.h"

namespace omis {
namespace {

using Clock = std::chrono::steady_clock;

// Texels are processed in square tiles: neighbours share cache lines and
// lights' per-point work, and a tile is the unit of progress and cancel.
constexpr int kTile = kBakeTile;
constexpr std::size_t kSetupTimingStride = 7;  // odd: not aligned with power-of-two rows

// A point of triangle t that lies on another mesh's face has its rays stopped
// there, as Cycles' do (scene/surface_contacts.h): it is moved behind both.
SurfacePoint on_contact(SurfacePoint p, std::uint32_t t, const SurfaceContacts* contacts) {
    if (contacts && contacts->on_other_surface(t, p.x) != SurfaceContacts::Contact::None)
        p.x = SurfaceContacts::behind_contact(p.x, p.n, p.ng);
    return p;
}

// A covered texel's footprint as a Footprint: positions and normals at the
// barycentrics of texel_footprint (uv_raster.h).
class TexelFootprint final : public Footprint {
public:
    TexelFootprint(const Mesh& mesh, const UvCoverage& cov, std::size_t i, bool smooth,
                   const SurfaceContacts* contacts = nullptr)
        : mesh_(mesh), cov_(cov), i_(i), map_(mesh, cov, i),
          ng_(mesh.geometric_normal(map_.triangle())), smooth_(smooth), contacts_(contacts) {}

    SurfacePoint at(double u, double v) const override {
        const auto b = map_.barycentrics(u, v);
        return point(b[0], b[1]);
    }
    SurfacePoint centre() const { return at(0.5, 0.5); }

    // The texels of a kAnchorBlock² block share their light tables' weights,
    // measured at the centre of one texel near the block's middle, when that
    // texel lies on the same triangle (else each texel is weighed alone).
    bool table_anchor(Anchor& anchor) const override {
        const std::size_t w = std::size_t(cov_.width), h = std::size_t(cov_.height);
        const std::size_t x = i_ % w, y = i_ / w;
        const std::size_t ax = std::min(w - 1, x / kAnchorBlock * kAnchorBlock + kAnchorBlock / 2);
        const std::size_t ay = std::min(h - 1, y / kAnchorBlock * kAnchorBlock + kAnchorBlock / 2);
        const std::size_t a = ay * w + ax;
        if (cov_.triangle[a] != map_.triangle()) return false;
        anchor.id = a;
        anchor.at = point(cov_.b1[a], cov_.b2[a]);
        return true;
    }

private:
    SurfacePoint point(double b1, double b2) const {
        const std::uint32_t t = map_.triangle();
        Vec3 n = smooth_ ? mesh_.shading_normal(t, b1, b2) : ng_;
        if (!(length(n) > 0)) n = ng_;
        return on_contact({mesh_.position(t, b1, b2), n, ng_}, t, contacts_);
    }

    // 4² texels a measurement: a 16th of the weights' cost (the spread and
    // round lights' dominated a one-sample pass), while the weights move by
    // what light changes over 4 texels.
    static constexpr std::size_t kAnchorBlock = 4;
    const Mesh& mesh_;
    const UvCoverage& cov_;
    std::size_t i_;
    TexelFootprintMap map_;
    Vec3 ng_;
    bool smooth_;
    const SurfaceContacts* contacts_;  // the receiver's contacts (issue 32), if any
};

// One point per triangle corner, inside its triangle as Cycles places it
// (vertex bakes are reduced from corners: see vertex_points.h).
std::vector<SurfacePoint> corner_points(const Mesh& mesh, bool smooth) {
    std::vector<SurfacePoint> points;
    for (std::uint32_t t = 0; t < mesh.num_triangles(); ++t)
        for (int k = 0; k < 3; ++k) {
            const Vec3 ng = mesh.geometric_normal(t);
            const CornerPoint c = inset_corner(mesh, t, k);
            Vec3 n = smooth ? mesh.shading_normal(t, c.b1, c.b2) : ng;
            if (!(length(n) > 0)) n = ng;
            points.push_back({mesh.position(t, c.b1, c.b2), n, ng});
        }
    return points;
}

// Running statistics of one point over passes, beside its running mean (kept
// in the output image itself, weighted by samples): Σ w_p² · own variance_p
// of luminance (the independent-draw formula), the running mean's variance as
// reported, and Σ w_p, w_p the samples of pass p. Doubles: variances of values
// beyond ~1e19 overflow a float.
struct PointState {
    double own_sum = 0;
    double variance = 0;
    double mean_weight = 0;    // Σ w_p: samples, except a tail block's (dyadic_schedule.h)
    std::uint32_t weight = 0;  // samples
    std::uint16_t passes = 0;
    bool done = false;
    // Draws per count a round (PointLighting::draws_per_count): > 1 where the
    // texel's centre sees no light, fixed per texel.
    std::uint8_t draws_per_count = 1;
};

// A point may stop for the noise target only after this many passes: a
// variance estimated from one or two small passes says too little.
constexpr int kMinPassesForNoiseTarget = 3;

double relative_error(const PointState& s, const float* mean) {
    if (s.weight == 0) return 0;
    const double value = luminance(Vec3(mean[0], mean[1], mean[2]));
    const double var = s.variance;
    if (value <= 0) return var > 0 ? 1.0 : 0.0;
    // A mean beyond the float range of the image has no meaningful noise.
    if (!std::isfinite(value) || !std::isfinite(var)) return std::numeric_limits<double>::infinity();
    return std::sqrt(std::max(0.0, var)) / value;
}

// How a sample budget splits into rounds: whole rounds of the settings'
// counts (P samples a round), then — when P does not divide the budget N — one
// final round holding P + (N mod P) samples, the extra spread over the
// techniques in proportion to their counts. Every technique keeps at least its
// own count in that round, so the combination there covers what it covers
// elsewhere and stays unbiased. A budget below P takes one whole round.
struct SampleBudget {
    int per_round = 0;
    int full_rounds = 1;
    std::vector<int> last;  // counts of the final round; empty: none
    int last_samples = 0;
};

SampleBudget plan_samples(const LightingContext& context, long long samples, int rounds) {
    SampleBudget b;
    const std::vector<int>& counts = context.settings.samples;
    for (int k : context.techniques) b.per_round += counts[k];
    if (b.per_round <= 0) {
        // Delta lights only (or nothing): a round is one evaluation of them at
        // one position of the footprint, and counts as one sample.
        b.per_round = 1;
        b.full_rounds = int(std::clamp<long long>(samples > 0 ? samples : rounds, 1, 1LL << 30));
        return b;
    }
    if (samples <= 0) {
        b.full_rounds = std::max(1, rounds);
        return b;
    }
    const long long P = b.per_round;
    const long long whole = std::max(1LL, samples / P), rest = samples >= P ? samples % P : 0;
    b.full_rounds = int(std::min<long long>(whole, 1LL << 30));
    if (rest == 0) return b;
    b.full_rounds -= 1;
    b.last = counts;
    long long given = 0;
    for (int k : context.techniques) {
        const long long extra = rest * counts[k] / P;
        b.last[k] += int(extra);
        given += extra;
    }
    for (int k : context.techniques)
        if (given < rest && counts[k] > 0) {
            ++b.last[k];
            ++given;
        }
    b.last_samples = int(P + rest);
    return b;
}

void validate(const Scene& scene, const BakeSettings& in) {
    if (!scene.committed())
        throw std::logic_error("scene: not committed (call commit before baking)");
    if (in.mesh >= scene.geometry().num_meshes())
        throw std::invalid_argument("mesh: id " + std::to_string(in.mesh) + " is out of range (" +
                                    std::to_string(scene.geometry().num_meshes()) + " meshes)");
    if (in.margin < 0) throw std::invalid_argument("margin: must not be negative");
    if (in.time_budget < 0 || !std::isfinite(in.time_budget))
        throw std::invalid_argument("time_budget: must be a non-negative number of seconds");
    if (in.noise_target < 0 || !std::isfinite(in.noise_target))
        throw std::invalid_argument("noise_target: must be a non-negative relative error");
    if (in.rounds_per_pass < 1) throw std::invalid_argument("rounds_per_pass: must be ≥ 1");
    if (in.first_tile > 0 || in.tile_count > 0) {
        if (in.target != BakeTarget::Lightmap)
            throw std::invalid_argument("tiles: tile ranges are for lightmap bakes only");
        const std::size_t tiles = bake_tile_count(in.width, in.height);
        if (in.first_tile >= tiles || in.tile_count > tiles - in.first_tile)
            throw std::invalid_argument("tiles: range " + std::to_string(in.first_tile) + " + " +
                                        std::to_string(in.tile_count) + " is outside the " +
                                        std::to_string(tiles) + " tiles of a " +
                                        std::to_string(in.width) + "×" + std::to_string(in.height) +
                                        " lightmap");
    }
}

// Where to shade: a lightmap's texels (those inside the UV layout are covered)
// or a mesh's triangle corners, visited in tiles.
struct BakeLayout {
    BakeLayout(const Mesh& mesh, const BakeSettings& settings) : target(settings.target) {
        if (target == BakeTarget::Lightmap) {
            coverage = rasterize_uv(mesh, settings.width, settings.height);
            width = settings.width;
            height = settings.height;
            count = coverage.triangle.size();
            tiles_x = (width + kTile - 1) / kTile;
            tiles_y = (height + kTile - 1) / kTile;
        } else {
            points = corner_points(mesh, settings.smooth_normals);
            width = int(points.size());
            height = 1;
            count = points.size();
            tiles_x = int((count + kTile * kTile - 1) / (kTile * kTile));
            tiles_y = 1;
        }
        tiles = std::size_t(tiles_x) * tiles_y;
        first_tile = settings.first_tile;
        end_tile = settings.tile_count ? first_tile + settings.tile_count : tiles;
    }
    bool lightmap() const { return target == BakeTarget::Lightmap; }
    bool partial() const { return first_tile > 0 || end_tile < tiles; }
    bool in_range(std::size_t i) const {
        if (!partial()) return true;
        const std::size_t x = i % std::size_t(width), y = i / std::size_t(width);
        const std::size_t tile = y / kTile * std::size_t(tiles_x) + x / kTile;
        return tile >= first_tile && tile < end_tile;
    }
    bool covered(std::size_t i) const {
        return !lightmap() || (coverage.is_covered(i) && in_range(i));
    }
    template <class Visit>
    void tile_points(std::size_t tile, Visit&& visit) const {
        if (!lightmap()) {
            const std::size_t begin = tile * kTile * kTile;
            for (std::size_t i = begin; i < std::min(count, begin + kTile * kTile); ++i) visit(i);
            return;
        }
        const int tx = int(tile % tiles_x), ty = int(tile / tiles_x);
        for (int y = ty * kTile; y < std::min(height, (ty + 1) * kTile); ++y)
            for (int x = tx * kTile; x < std::min(width, (tx + 1) * kTile); ++x)
                visit(std::size_t(y) * width + x);
    }

    BakeTarget target;
    UvCoverage coverage;
    std::vector<SurfacePoint> points;  // vertex bakes only
    int width = 0, height = 0, tiles_x = 0, tiles_y = 0;
    std::size_t count = 0, tiles = 0;
    std::size_t first_tile = 0, end_tile = 0;  // the tiles this bake shades
};

// One pass over every point that is not done.
struct Pass {
    int first_round = 0, rounds = 0;
    const int* counts = nullptr;  // null: the settings' counts
    std::uint32_t samples = 0;    // per point
    double weight = 0;            // in the running means; 0: samples (a tail block's is less)
    bool tail = false;            // a tail block after a time budget's last net
    const std::vector<DrawnRounds>* earlier = nullptr;  // allocated tiles: their calls so far
};

// Sample allocation (issue 10; BakeSettings::allocate_samples). The first pass
// is every tile's pilot: it records the samples of some of the tile's texels
// (at most kPilotSamples, so choosing costs little beside shading), and the
// tile's shares follow from them (mis/allocation.h). Later passes draw the
// same samples per texel as without allocation, in rounds of at least
// kMinAllocatedRound samples (and kRoundPerTechnique per technique, so that
// the shares can move) split by those shares, each technique keeping at
// least kAllocationFloor of them and one sample a round: a technique that
// alone covers what the pilot did not see keeps drawing (a defensive mix).
constexpr int kPilotSamples = 512;
constexpr int kMinAllocatedRound = 8, kRoundPerTechnique = 4;
constexpr double kAllocationFloor = 0.05;

// A tile's shares and every call its points took so far (the sequences of a
// later call continue after them).
struct TileAllocation {
    std::vector<double> shares;
    std::vector<DrawnRounds> drawn;
    std::deque<std::vector<int>> counts;  // the calls' counts (stable addresses)
    int next_round = 0;
};

// A point's estimate of one pass, before it joins the running mean.
struct Shaded {
    std::size_t i;
    double value[3];
    double own_variance;      // luminance, independent-draw formula
    StreamEstimates streams;  // when the bake has several streams
    int draws_per_count;      // PointLighting::draws_per_count
};

// A point's streams over all passes so far: Σ w·estimate and Σ w per stream
// (w: the stream's samples in a pass). Their spread is the error of the
// point's running mean — the passes of one stream continue one sequence, so
// per-pass errors do not add as if independent (that over-stated a noise
// target's error up to 10× and stopped it late).
struct StreamTally {
    double sum[kMaxSampleStreams] = {}, weight[kMaxSampleStreams] = {};
    // Var(mean) = Σ w_s (e_s − ē)² / ((S − 1) W); -1 with fewer than two streams.
    double variance() const {
        double total = 0, mean = 0;
        int used = 0;
        for (int s = 0; s < kMaxSampleStreams; ++s)
            if (weight[s] > 0) {
                total += weight[s];
                mean += sum[s];
                ++used;
            }
        if (used < 2) return -1;
        mean /= total;
        double spread = 0;
        for (int s = 0; s < kMaxSampleStreams; ++s)
            if (weight[s] > 0) {
                const double d = sum[s] / weight[s] - mean;
                spread += weight[s] * d * d;
            }
        return spread / ((used - 1) * total);
    }
};

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
    void accumulate(const Pass& pass, const std::vector<Shaded>& tile);
    // The pass as the tile's points took it (an allocated tile's own rounds).
    Pass shade_tile(PointLighting& shader, std::size_t tile, const Pass& pass,
                    std::vector<Shaded>& out);
    void pilot_tile(PointLighting& shader, std::size_t tile, const Pass& pass,
                    std::vector<Shaded>& out);
    Pass allocated_pass(TileAllocation& t, const Pass& pass);
    void fill_allocation_stats();
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
    bool noise_target_met() const;
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
    std::vector<PointState> state_;
    std::vector<StreamTally> tallies_;  // per point, when settings_.lighting.streams > 1
    tbb::enumerable_thread_specific<std::vector<double>> spread_scratch_;  // accumulate's
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
    std::vector<TileAllocation> tiles_;
};

// The key a bake's measured pass cost is kept under in its Scene: what sets
// the cost of a round (the mesh and its points, the techniques and their
// counts, the streams, the threads), not the strategy (which costs per pass,
// not per round) nor the budget.
std::uint64_t bake_shape(const BakeSettings& s, const BakeLayout& layout) {
    std::ostringstream key;
    key << s.mesh << ' ' << int(s.target) << ' ' << layout.width << 'x' << layout.height << ' '
        << layout.count << ' ' << s.smooth_normals << ' ' << s.lighting.streams << ' '
        << tbb::this_task_arena::max_concurrency() << ' ' << layout.first_tile << '-'
        << layout.end_tile;
    for (std::size_t k = 0; k < s.lighting.techniques.size(); ++k)
        key << ' ' << s.lighting.techniques[k].name() << ':'
            << (k < s.lighting.samples.size() ? s.lighting.samples[k] : 0);
    return std::hash<std::string>{}(key.str());
}

BakeSettings with_receiver(const Scene& scene, BakeSettings settings) {
    settings.lighting.receiver = scene.mesh_receiver(settings.mesh);  // render/receiver.h
    settings.lighting.points_on_mesh = settings.mesh;  // texels and corners lie on it
    // A noise target stops on the error, so the error must be measured, not
    // bounded: independent streams (DirectLightingSettings::streams).
    if (settings.noise_target > 0) settings.lighting.streams = kMaxSampleStreams;
    return settings;
}

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
      progressive_(settings_.time_budget > 0 || settings_.noise_target > 0),
      state_(layout_.count),
      tallies_(settings_.lighting.streams > 1 ? layout_.count : 0),
      shaders_([this] { return PointLighting(context_); }) {
    result_.width = layout_.width;
    result_.height = layout_.height;
    result_.value.assign(layout_.count * 3, 0.f);  // the running means
    buried_ = count_buried();
    // Corners on another mesh's face: moved behind it (on_contact).
    for (std::size_t i = 0; i < layout_.points.size(); ++i)
        layout_.points[i] = on_contact(layout_.points[i], std::uint32_t(i / 3), &contacts_);
    // Uncovered texels are never shaded: they count as done for the noise target.
    std::size_t to_shade = 0;
    for (std::size_t i = 0; i < layout_.count; ++i) {
        if (!layout_.covered(i)) state_[i].done = true;
        to_shade += layout_.covered(i);
    }
    const long long samples_per_point =
        (long long)budget_.full_rounds * budget_.per_round + budget_.last_samples;
    total_work_ = double(std::max<std::size_t>(1, to_shade)) *
                  double(std::max<long long>(1, samples_per_point));
    context_.keep_going = [this] { return keep_going(); };
    // The points are 0 … count − 1; their slots (~48 bytes each, allocated,
    // zeroed and freed by every bake) only where the shading keeps tables: a
    // 128² samples=1 bake took 1.04–1.57× as long with them (budgets.txt).
    if (context_.keeps_texel_tables) context_.texel_tables.index_points(layout_.count);

    // Under a time budget the first pass — the part a budget cannot cut — is
    // a single round, so small budgets are not eaten by it; it also measures
    // what a round costs here. The optimal strategies solve per pass, and a
    // one-round pass falls back to balance (too few samples to fit α): its
    // estimate, averaged in by samples, would add balance's far larger
    // variance per sample. For them it is a probe: the result if the budget
    // ends there, else replaced by the passes after it, which start again at
    // round 0 (the same draws) and take rounds_per_pass or more.
    const bool under_time = settings_.time_budget > 0;
    const bool optimal = fits_per_pass();
    next_rounds_ = !progressive_ ? budget_.full_rounds
                   : under_time  ? 1
                                 : settings_.rounds_per_pass;
    later_min_rounds_ = under_time && optimal ? settings_.rounds_per_pass : 1;
    probe_ = under_time && optimal && budget_.full_rounds > 1;
    last_done_ = budget_.last.empty();
    allocate_ = settings_.allocate_samples && is_optimal(settings_.lighting.strategy) &&
                context_.techniques.size() >= 2 && budget_.full_rounds >= 2;
    dyadic_ = under_time && settings_.noise_target <= 0 && !allocate_;
    // Points shaded in more than one pass keep where their table draws stand
    // (LightingContext::draw_counts), which a later pass continues from,
    // whether their centre is in the shadow of most of their light
    // (shadow_verdicts), the reach behind their uniform or power tables
    // (table_reach), the radius of their footprint's region (region_radii) and
    // the light tree's branching there (region_branching).
    if (progressive_ || allocate_ || !budget_.last.empty()) {
        context_.keep_draw_counts(layout_.count);
        context_.keep_shadow_verdicts(layout_.count);
        context_.keep_table_reach(layout_.count);
        if (layout_.lightmap()) {
            context_.keep_region_radii(layout_.count);
            context_.keep_region_branching(layout_.count);
        }
    }
    if (allocate_) {
        probe_ = false;  // the first pass is the allocation's pilot, not replaced
        tiles_.resize(layout_.tiles);
        // A bake of a sample budget: a quarter of it is the pilot, the rest one pass.
        if (!progressive_) next_rounds_ = std::max(1, budget_.full_rounds / 4);
    }
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
    if (!layout_.covered(i) || state_[i].done || cancel_.load(std::memory_order_relaxed)) return;
    Shaded r{i, {}, 0, {}, 1};
    double variance[3], own[3];
    StreamEstimates* streams = tallies_.empty() ? nullptr : &r.streams;
    // The first pass times its set-up and sampling on every
    // kSetupTimingStride-th point only: clock reads at every point cost ~5 %
    // of a one-round pass (four then, six now), and time_pass needs only the
    // ratios of set-up and rounds to shading.
    shader.setup_timing.on = pass_count_ == 0 && i % kSetupTimingStride == 0;
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

// A tile's points join their running means. Their variance: the
// independent-draw formula over the passes (stable per point, but too high
// for correlated draws); with several streams, scaled by the tile's ratio of
// the streams' spread to it (many degrees of freedom once pooled over the
// tile), or the point's own streams' spread where that is larger.
void Baker::accumulate(const Pass& pass, const std::vector<Shaded>& tile) {
    std::vector<double>& spread = spread_scratch_.local();
    spread.assign(tile.size(), -1);
    double sum_spread = 0, sum_own = 0;
    for (std::size_t t = 0; t < tile.size(); ++t) {
        const Shaded& r = tile[t];
        PointState& s = state_[r.i];
        ++s.passes;
        s.weight += pass.samples;
        s.draws_per_count = std::uint8_t(r.draws_per_count);
        const double w = pass.weight > 0 ? pass.weight : double(pass.samples);
        s.mean_weight += w;
        const double weight = w / s.mean_weight;
        float* mean = &result_.value[3 * r.i];
        for (int c = 0; c < 3; ++c)  // a mean past the float range stays infinite
            if (!std::isinf(mean[c])) mean[c] += float((r.value[c] - mean[c]) * weight);
        s.own_sum += w * w * r.own_variance;
        s.variance = s.own_sum / (s.mean_weight * s.mean_weight);
        if (tallies_.empty()) continue;
        StreamTally& tally = tallies_[r.i];
        const double per_round = double(pass.samples) / pass.rounds;
        for (int k = 0; k < kMaxSampleStreams; ++k) {
            const double w = r.streams.rounds[k] * per_round;
            tally.sum[k] += w * r.streams.luminance[k];
            tally.weight[k] += w;
        }
        spread[t] = tally.variance();
        if (spread[t] < 0) continue;
        sum_spread += spread[t];
        sum_own += s.variance;
    }
    const double ratio = sum_own > 0 ? sum_spread / sum_own : 1.0;
    for (std::size_t t = 0; t < tile.size(); ++t) {
        PointState& s = state_[tile[t].i];
        // The larger of the two: a tile's ratio comes mostly from its smooth
        // texels, and would understate a texel whose own streams disagree
        // more (rare bright samples, a shadow edge).
        if (spread[t] >= 0) s.variance = std::max(s.variance * ratio, spread[t]);
        // A point whose samples all agreed (nothing seen yet, typically a
        // shadowed texel that rare samples light) gives no error estimate:
        // it is not done, but keeps sampling while others still need to.
        if (settings_.noise_target > 0 && s.passes >= kMinPassesForNoiseTarget &&
            s.variance > 0 && relative_error(s, &result_.value[3 * tile[t].i]) <=
                                  settings_.noise_target)
            s.done = true;
    }
}

Pass Baker::shade_tile(PointLighting& shader, std::size_t tile, const Pass& pass,
                       std::vector<Shaded>& out) {
    if (!allocate_) {
        layout_.tile_points(tile, [&](std::size_t i) { shade_point(shader, i, pass, out); });
        return pass;
    }
    TileAllocation& t = tiles_[tile];
    if (t.shares.empty()) {
        pilot_tile(shader, tile, pass, out);
        return pass;
    }
    Pass allocated = allocated_pass(t, pass);
    layout_.tile_points(tile, [&](std::size_t i) { shade_point(shader, i, allocated, out); });
    t.drawn.push_back({allocated.first_round, allocated.rounds, allocated.counts});
    t.next_round += allocated.rounds;
    allocated.earlier = nullptr;  // t.drawn now holds this call too
    return allocated;
}

// The tile's first pass with the settings' counts, recording every stride-th
// texel's samples, each texel's integrand scaled by 1/its estimate (so bright
// texels do not decide for the dim ones); then the tile's shares.
void Baker::pilot_tile(PointLighting& shader, std::size_t tile, const Pass& pass,
                       std::vector<Shaded>& out) {
    const std::vector<int>& counts = settings_.lighting.samples;
    AllocationPilot pilot(int(counts.size()), 1, counts);
    const int stride =
        std::max(1, int(std::ceil(double(kTile * kTile) * pass.samples / kPilotSamples)));
    int visited = 0;
    layout_.tile_points(tile, [&](std::size_t i) {
        const bool record = visited++ % stride == 0;
        const std::size_t before = out.size();
        shader.record_into(record ? &pilot : nullptr);
        shade_point(shader, i, pass, out);
        shader.record_into(nullptr);
        const double value =
            out.size() > before ? luminance(Vec3(out.back().value[0], out.back().value[1],
                                                 out.back().value[2]))
                                : 0.0;
        if (record) pilot.end_point(value > 0 && std::isfinite(value) ? 1 / value : 0.0,
                                    out.size() > before ? pass.rounds : 0);
    });
    TileAllocation& t = tiles_[tile];
    t.shares.assign(counts.begin(), counts.end());  // the pilot's own split
    if (pilot.rounds() > 0 && pilot.samples() > 0) {
        const double floor =
            std::min(kAllocationFloor, 0.5 / double(context_.techniques.size()));
        t.shares = optimal_shares(pilot, pilot.cost(), floor);
    }
    t.drawn.push_back({pass.first_round, pass.rounds, pass.counts});
    t.next_round = pass.first_round + pass.rounds;
}

// A later pass of an allocated tile: the pass's samples per texel in rounds
// of the tile's shares — as many rounds as keep at least kMinAllocatedRound
// samples each, kRoundPerTechnique a technique (a pass's last partial round:
// one round).
Pass Baker::allocated_pass(TileAllocation& t, const Pass& pass) {
    const int P = budget_.per_round;
    const int least = std::max<int>(kMinAllocatedRound,
                                    kRoundPerTechnique * int(context_.techniques.size()));
    int rounds = 1;
    if (!pass.counts) {
        int group = pass.rounds;  // settings rounds per allocated round
        for (int g = 1; g <= pass.rounds; ++g)
            if (pass.rounds % g == 0 && g * P >= least) {
                group = g;
                break;
            }
        rounds = pass.rounds / group;
    }
    t.counts.push_back(counts_from_shares(t.shares, int(pass.samples) / rounds));
    Pass p = pass;
    p.first_round = t.next_round;
    p.rounds = rounds;
    p.counts = t.counts.back().data();
    p.earlier = &t.drawn;
    return p;
}

// What the allocation did: each technique's mean share (and range) over the
// tiles that chose one.
void Baker::fill_allocation_stats() {
    BakeStats& stats = result_.stats;
    if (!allocate_) return;
    const std::size_t T = settings_.lighting.techniques.size();
    std::vector<double> sum(T, 0.0), lo(T, 1.0), hi(T, 0.0);
    std::size_t n = 0;
    for (const TileAllocation& t : tiles_) {
        if (t.shares.empty() || t.drawn.size() < 2) continue;  // no allocated pass
        const double total = std::accumulate(t.shares.begin(), t.shares.end(), 0.0);
        for (std::size_t k = 0; k < T; ++k) {
            const double w = t.shares[k] / total;
            sum[k] += w;
            lo[k] = std::min(lo[k], w);
            hi[k] = std::max(hi[k], w);
        }
        ++n;
    }
    std::ostringstream s;
    s << "sample allocation: pilot pass of " << (tiles_.empty() || tiles_[0].drawn.empty()
                                                       ? 0 : tiles_[0].drawn[0].rounds)
      << " rounds, then " << n << " tiles split their samples (floor "
      << kAllocationFloor << " a technique)";
    for (std::size_t k = 0; k < T && n > 0; ++k) {
        stats.allocated_shares.push_back(sum[k] / n);
        s << "; " << settings_.lighting.techniques[k].name() << " " << sum[k] / n << " ("
          << lo[k] << "–" << hi[k] << ")";
    }
    stats.allocation = s.str();
}

void Baker::run_pass(const Pass& pass) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(layout_.first_tile, layout_.end_tile, 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
        PointLighting& shader = shaders_.local();
        std::vector<Shaded> shaded_tile;
        for (std::size_t tile = range.begin(); tile != range.end(); ++tile) {
            if (cancel_.load(std::memory_order_relaxed)) return;
            shaded_tile.clear();
            accumulate(shade_tile(shader, tile, pass, shaded_tile), shaded_tile);
        }
    });
}

// The next pass of the schedule, cut to what the time budget still fits (as
// the passes so far predict its duration); false when the bake ends here.
bool Baker::plan_pass(Pass& pass) {
    // A pass meant to take the time left ends the bake, unless the prediction
    // behind it was pessimistic (early passes carry the warm-up) and a tenth
    // of the budget or more is still left: a budget is time to use.
    if (time_ends_) {
        if (settings_.time_budget - elapsed() < 0.1 * settings_.time_budget) {
            status_ = BakeStatus::TimeBudget;
            return false;
        }
        time_ends_ = false;
    }
    if (dyadic_ && pass_count_ > 0 && done_rounds_ < budget_.full_rounds)
        return plan_dyadic_pass(pass);
    pass.first_round = done_rounds_;
    if (done_rounds_ < budget_.full_rounds) {
        pass.rounds = std::min(next_rounds_, budget_.full_rounds - done_rounds_);
    } else if (!last_done_) {
        pass.rounds = 1;
        pass.counts = budget_.last.data();
    } else {
        return false;
    }
    if (settings_.time_budget > 0 && pass_count_ > 0) {
        const double fits = timer_.fit(settings_.time_budget - elapsed());
        const double fit_rounds = fits / budget_.per_round;
        const int rounds_left = budget_.full_rounds - done_rounds_;
        // When the time left would cut the pass after this one short (less
        // than this pass fits again), this pass takes all of it and is the
        // last: a small final pass adds few samples, and as its estimate joins
        // the others' as an independent one, its poor error raises the estimate.
        if (!pass.counts && fit_rounds < 2.0 * pass.rounds && fit_rounds < rounds_left) {
            pass.rounds = int(std::max(0.0, fit_rounds));
            time_ends_ = true;
            // An optimal strategy skips a last pass far smaller than the one
            // before: its own solve (balance, below 2(k + 1) samples) joins
            // the others' and raises the error more than its samples lower it.
            if (fits_per_pass() && 4 * pass.rounds < last_pass_rounds_)
                pass.rounds = 0;
        } else if (!pass.counts && settings_.noise_target <= 0) {
            // Few passes: each costs a fixed part (per-point set-up, the
            // optimal strategies' solve). A pass takes half the time left, as
            // the passes so far predict, but at most 4× the pass before it,
            // whose time predicts its own: one round (milliseconds) measures
            // the cost too roughly to size a pass of seconds.
            pass.rounds = std::min({rounds_left, std::max(pass.rounds, int(0.5 * fit_rounds)),
                                    4 * last_pass_rounds_});
        }
        if (pass.rounds < 1 || (pass.counts && fits < budget_.last_samples)) {
            status_ = BakeStatus::TimeBudget;
            return false;
        }
    }
    pass.samples = pass.counts ? std::uint32_t(budget_.last_samples)
                               : std::uint32_t(pass.rounds * budget_.per_round);
    return true;
}

// The next pass of a time budget, to a power of two of rounds or a tail after
// one (dyadic_schedule.h).
bool Baker::plan_dyadic_pass(Pass& pass) {
    const double fit = timer_.fit(settings_.time_budget - elapsed()) / budget_.per_round;
    // An optimal strategy's probe is replaced by a first net of
    // rounds_per_pass only where that still fits. Where it does not (small
    // budgets, costly first passes: the race's 0.25 s on 64 lights ended at
    // 0.11 s with the probe alone), the probe stays as the first round and the
    // passes after it follow as for balance (below 2(k + 1) samples a pass
    // solves as balance anyway).
    DyadicPass next;
    if (replace_probe_) {
        const PassAfterProbe after =
            pass_after_probe(last_pass_rounds_, fit, later_min_rounds_, budget_.full_rounds);
        next = after.pass;
        if (after.keep_probe) {
            replace_probe_ = false;
            done_rounds_ = last_pass_rounds_;
            if (power_of_two_floor(done_rounds_) == done_rounds_) record_net_end();
        }
    } else {
        next = next_dyadic_pass(done_rounds_, fit, later_min_rounds_,
                                budget_.full_rounds - done_rounds_);
    }
    if (next.rounds < 1) {
        status_ = BakeStatus::TimeBudget;
        return false;
    }
    pass.first_round = done_rounds_;
    pass.rounds = next.rounds;
    pass.samples = std::uint32_t(pass.rounds * budget_.per_round);
    pass.tail = next.tail;
    if (next.tail && 2 * next.rounds != done_rounds_)
        pass.weight = budget_.per_round * tail_weight(power_of_two_floor(done_rounds_),
                                                      next.rounds, rate_.tail_alpha());
    return true;
}

// At a power-of-two end: how much the running means moved since the last one
// (mean square relative change over the baked texels, as the race measures
// error: ε = 1 % of the mean keeps dark texels finite), for NetRate.
void Baker::record_net_end() {
    double sum_change = 0, sum_value = 0;
    std::size_t covered = 0;
    const bool first = net_end_luminance_.empty();
    if (first) net_end_luminance_.assign(layout_.count, 0.f);
    for (std::size_t i = 0; i < layout_.count; ++i)
        if (layout_.covered(i)) {
            const float* v = &result_.value[3 * i];
            sum_value += luminance(Vec3(v[0], v[1], v[2]));
            ++covered;
        }
    const double eps = 0.01 * (covered ? sum_value / double(covered) : 0.0);
    for (std::size_t i = 0; i < layout_.count; ++i) {
        if (!layout_.covered(i)) continue;
        const float* v = &result_.value[3 * i];
        const double now = luminance(Vec3(v[0], v[1], v[2]));
        const double d = now - net_end_luminance_[i];
        if (std::isfinite(d)) sum_change += d * d / (now * now + eps * eps + 1e-300);
        net_end_luminance_[i] = float(now);
    }
    rate_.add(done_rounds_, first || !covered ? 0.0 : sum_change / double(covered));
}

bool Baker::noise_target_met() const {
    return settings_.noise_target > 0 &&
           std::all_of(state_.begin(), state_.end(), [&](const PointState& s) {
               return s.done || (s.passes >= kMinPassesForNoiseTarget && s.variance == 0);
           });
}

// A time budget's first pass where an earlier bake of the same shape measured
// its passes (Scene::measured_pass_cost): sized by that measure
// (measured_first_pass), in place of the one-round pass that
// otherwise measures the cost — and which an optimal strategy then replaces
// (its probe). On emissive_mesh at 128² a round takes 12–15 ms and a first
// pass ~6.5 ms more: in a 0.05 s budget the probe and one more round ended at
// one or two samples by a few ms either way, where two rounds in one pass
// take 37 ms (budgets.txt). Not taken below two rounds: one round is the
// probe's own size.
void Baker::size_first_pass() {
    if (!dyadic_) return;
    const auto cost = scene_.measured_pass_cost(shape_);
    if (!cost || !(cost->round > 0)) return;
    const double left = settings_.time_budget - elapsed() - cost->first_pass_fixed;
    const int rounds = measured_first_pass(left / cost->round, budget_.full_rounds);
    if (rounds < 2) return;
    next_rounds_ = rounds;
    probe_ = false;  // a first net (or one too small for a solve: as a kept probe)
}

// What this bake's passes cost, for the next bake of its shape: the first
// pass's fixed part, and a round at the rate the last pass ran, blended with
// the earlier bakes' (blend_round_cost).
void Baker::remember_pass_cost() const {
    const double round = timer_.per_sample() * budget_.per_round;
    if (status_ == BakeStatus::Cancelled || first_pass_fixed_ < 0 || !(round > 0)) return;
    Scene::PassCost earlier;
    if (const auto known = scene_.measured_pass_cost(shape_)) earlier = *known;
    const BlendedRoundCost blend =
        blend_round_cost(earlier.round, earlier.rounds, round, last_pass_rounds_);
    scene_.remember_pass_cost(shape_, {first_pass_fixed_, blend.seconds, blend.rounds});
}

void Baker::run_passes() {
    size_first_pass();
    const double sampling_start = elapsed();
    for (;;) {
        Pass pass;
        if (!plan_pass(pass)) return;
        if (replace_probe_) forget_probe();
        const double pass_start = elapsed();
        run_pass(pass);
        time_pass(pass.samples, elapsed() - pass_start);
        ++pass_count_;
        if (cancel_) {
            status_ = BakeStatus::Cancelled;
            return;
        }
        record_pass(sampling_start, pass.tail);
        if (pass.counts) last_done_ = true;
        if (!pass.counts) last_pass_rounds_ = pass.rounds;
        if (probe_ && pass_count_ == 1) {
            replace_probe_ = true;  // the next pass, if any, starts again at round 0
        } else {
            done_rounds_ += pass.rounds;
            if (dyadic_ && power_of_two_floor(done_rounds_) == done_rounds_) record_net_end();
        }
        // Doubling keeps the per-pass cost small; under a noise target passes
        // grow by half only, so a texel overshoots its target by at most
        // √1.5 ≈ 1.22 in error.
        const double growth = settings_.noise_target > 0 ? 1.5 : 2.0;
        next_rounds_ = int(std::min<double>(
            1 << 24, std::max<double>(later_min_rounds_, std::ceil(growth * pass.rounds))));
        if (!progressive_) next_rounds_ = budget_.full_rounds;  // after an allocation pilot
        if (noise_target_met()) {
            status_ = BakeStatus::NoiseTarget;
            return;
        }
    }
}

// The pass that ran, for the timer. Of the first pass, only what a later pass
// of its size repeats: all of it but the set-up of the tables its points keep
// (PointLighting::SetupTiming: 8–39 % of a one-round first pass on the race's
// scenes, which made the second pass look that much longer and could end a
// 0.05 s budget a round early); and of that, the part outside the rounds'
// sampling is the fixed part of every later pass.
void Baker::time_pass(std::uint32_t samples, double seconds) {
    if (pass_count_ > 0) {
        timer_.add(samples, seconds);
        return;
    }
    double setup = 0, shading = 0, rounds = 0;
    for (PointLighting& shader : shaders_) {
        setup += shader.setup_timing.kept_setup;
        shading += shader.setup_timing.shading;
        rounds += shader.setup_timing.rounds;
        shader.setup_timing = {};
    }
    if (!(shading > 0)) {
        timer_.add(samples, seconds);
        return;
    }
    const double repeated = std::clamp(1.0 - setup / shading, 0.0, 1.0);
    first_pass_fixed_ = seconds * std::max(0.0, 1.0 - rounds / shading);
    timer_.add(samples, seconds * repeated);
    timer_.set_fixed(seconds * std::max(0.0, repeated - rounds / shading));
}

// The probe pass's estimates leave the running means, the error tallies and
// the sample count (the next pass's estimates replace them).
void Baker::forget_probe() {
    replace_probe_ = false;
    net_end_luminance_.clear();
    rate_.reset();
    for (std::size_t i = 0; i < layout_.count; ++i) {
        if (!layout_.covered(i)) continue;
        replaced_draws_ += std::uint64_t(state_[i].weight) * state_[i].draws_per_count;
        state_[i] = PointState{};
        if (!tallies_.empty()) tallies_[i] = StreamTally{};
        for (int c = 0; c < 3; ++c) result_.value[3 * i + c] = 0.f;
    }
}

// The bake's convergence after a pass (convergence.h): what the running means
// have reached, and when.
void Baker::record_pass(double sampling_start, bool tail) {
    const double seconds = elapsed() - sampling_start;
    double sum_error = 0, sum_samples = 0;
    std::size_t covered = 0;
    for (std::size_t i = 0; i < layout_.count; ++i) {
        if (!layout_.covered(i)) continue;
        sum_error += relative_error(state_[i], &result_.value[3 * i]);
        sum_samples += state_[i].weight;
        ++covered;
    }
    BakePassRecord r;
    r.seconds = seconds;
    r.samples_per_texel = covered ? sum_samples / double(covered) : 0;
    r.mean_relative_error = covered ? sum_error / double(covered) : 0;
    r.tail = tail;
    result_.stats.convergence.push_back(r);
}

// The running means are the values; the noise, mask and sample counts join them.
void Baker::write_outputs() {
    const std::size_t count = layout_.count;
    result_.noise.assign(count, 0.f);
    result_.mask.assign(count, 0.f);
    result_.samples.assign(count, 0);
    BakeStats& stats = result_.stats;
    double sum_error = 0, sum_passes = 0;
    std::size_t n_covered = 0;
    for (std::size_t i = 0; i < count; ++i) {
        result_.samples[i] = state_[i].weight;
        if (!layout_.covered(i)) continue;
        const PointState& s = state_[i];
        const double err = relative_error(s, &result_.value[3 * i]);
        result_.noise[i] = float(err);
        result_.mask[i] = 1.f;
        sum_error += err;
        sum_passes += s.passes;
        stats.samples += s.weight;
        stats.shadowed_texels += s.draws_per_count > 1;
        stats.max_relative_error = std::max(stats.max_relative_error, err);
        ++n_covered;
    }
    stats.covered = n_covered;
    stats.buried_texels = buried_;
    stats.mean_relative_error = n_covered ? sum_error / n_covered : 0;
    stats.passes_per_texel = n_covered ? sum_passes / n_covered : 0;
}

// Covered texels (corners) whose centre lies inside other geometry, or on a
// face of another mesh turned its way (BakeStats::buried_texels). Only where
// some geometry can occlude the points, and, but for contacts, only points in
// another mesh's bounds trace (one ray where they are not inside).
std::size_t Baker::count_buried() const {
    if (!context_.plan.shadow_rays) return 0;
    const GeometryScene& geometry = scene_.geometry();
    std::atomic<std::size_t> buried{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, layout_.count, 256),
                      [&](const tbb::blocked_range<std::size_t>& range) {
        std::size_t here = 0;
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            if (!layout_.covered(i)) continue;
            SurfacePoint p;
            std::uint32_t t;
            if (layout_.lightmap()) {
                p = TexelFootprint(mesh_, layout_.coverage, i, settings_.smooth_normals).centre();
                t = layout_.coverage.triangle[i];
            } else {  // before on_contact moves them
                t = std::uint32_t(i / 3);
                p = layout_.points[i];
            }
            here += contacts_.on_other_surface(t, p.x) == SurfaceContacts::Contact::Facing ||
                    (contacts_.may_be_inside(p.x) && inside_other_geometry(geometry, p.x, p.n, p.ng));
        }
        buried.fetch_add(here, std::memory_order_relaxed);
    });
    return buried.load();
}

// The margin around UV islands: copies of the texels it extends.
// (A tile range leaves it to fill_bake_margin, once the ranges are together.)
void copy_margin(const UvCoverage& coverage, const Mesh& mesh, const BakeSettings& settings,
                 float* value, float* noise) {
    const std::vector<std::int64_t> source =
        settings.margin_type == MarginType::AdjacentFaces
            ? adjacent_margin_sources(coverage, mesh, settings.margin)
            : margin_sources(coverage, settings.margin);
    for (std::size_t i = 0; i < coverage.triangle.size(); ++i) {
        if (coverage.is_covered(i) || source[i] < 0) continue;
        for (int c = 0; c < 3; ++c) value[3 * i + c] = value[3 * source[i] + c];
        noise[i] = noise[source[i]];
    }
}

void Baker::fill_margin() {
    if (!layout_.lightmap() || settings_.margin <= 0 || layout_.partial()) return;
    copy_margin(layout_.coverage, mesh_, settings_, result_.value.data(), result_.noise.data());
}

void Baker::fill_stats() {
    BakeStats& stats = result_.stats;
    for (const PointLighting& s : shaders_) {
        stats.draws += s.counters.samples;
        stats.rays_traced += s.counters.rays;
        stats.mis_systems += s.counters.systems;
    }
    stats.draws -= std::min(stats.draws, replaced_draws_);  // counts what the values hold
    stats.status = status_;
    stats.passes = pass_count_;
    stats.texels = layout_.count;
    stats.degenerate_uv_triangles = layout_.coverage.degenerate_uv_triangles;
    stats.overlapping_texels = layout_.coverage.overlapping_texels;
    stats.samples_per_texel = stats.covered ? double(stats.samples) / stats.covered : 0;
    stats.draws_per_texel = stats.covered ? double(stats.draws) / stats.covered : 0;
    stats.plan = context_.plan.to_string();
    for (std::size_t k = 0; k < settings_.lighting.techniques.size(); ++k) {
        stats.techniques.push_back(settings_.lighting.techniques[k].name());
        stats.samples_per_round.push_back(settings_.lighting.samples[k]);
    }
    stats.halving = predict_halving(stats.convergence);
    stats.seconds = elapsed();
}

BakeResult Baker::run() {
    run_passes();
    remember_pass_cost();
    write_outputs();
    fill_margin();
    fill_stats();
    fill_allocation_stats();
    return std::move(result_);
}

}  // namespace

void fill_bake_margin(const Scene& scene, const BakeSettings& settings, float* value,
                      float* noise) {
    BakeSettings whole = settings;
    whole.first_tile = whole.tile_count = 0;
    validate(scene, whole);
    if (whole.target != BakeTarget::Lightmap || whole.margin <= 0) return;
    const Mesh& mesh = scene.geometry().mesh(whole.mesh);
    copy_margin(rasterize_uv(mesh, whole.width, whole.height), mesh, whole, value, noise);
}

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
    const auto start = Clock::now();
    validate(scene, in);
    BakeSettings settings = in;
    if (settings.lighting.techniques.empty())
        default_techniques(scene, settings.lighting.techniques, settings.lighting.samples,
                           &settings.lighting.shadowed_draws);
    return Baker(scene, settings, progress, start).run();
}

}  // namespace omis
