// Baking direct lighting (E/π, SPEC §3) into a mesh's UV lightmap or onto its
// vertices/corners, in parallel tiles, under a sample, time or noise budget.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bake/convergence.h"
#include "bake/uv_raster.h"
#include "render/direct_lighting.h"

namespace omis {

enum class BakeTarget { Lightmap, Vertices, Corners };
enum class BakeStatus { Complete, TimeBudget, NoiseTarget, Cancelled };
const char* bake_status_name(BakeStatus status);

struct BakeSettings {
    // Techniques, samples per round, strategy, seed. Empty techniques: the
    // effect plan's default choice. The sample budget: `samples` per texel
    // exactly when > 0 (whole rounds plus one final round holding the rest;
    // at least one round), else `lighting.rounds` rounds.
    DirectLightingSettings lighting;
    long long samples = 0;
    BakeTarget target = BakeTarget::Lightmap;
    std::uint32_t mesh = 0;
    int width = 0, height = 0;  // lightmap size
    int margin = 16;            // texels of extension around UV islands
    MarginType margin_type = MarginType::Extend;  // what fills them (uv_raster.h)
    bool smooth_normals = true; // interpolate corner normals (else flat)
    double time_budget = 0;     // seconds; 0 = none
    double noise_target = 0;    // relative standard error per texel; 0 = none
    // Rounds of the first pass when a noise target asks for progressive
    // passes (later passes grow); under a time budget the first pass is one
    // round (the optimal strategies, which solve per pass, go on with this
    // many or more from round 0 where that fits, else keep the first round)
    // unless an earlier bake of the same shape measured what fits (bake_schedule.cpp:
    // Baker::size_first_pass),
    // and later passes end on powers of two of rounds, with a
    // tail block weighted by its measured error (bake/dyadic_schedule.h).
    // Each pass is one estimate per texel (its own solve); passes are
    // averaged, weighted by samples (a tail block by less).
    int rounds_per_pass = 4;
    int threads = 0;            // worker threads; 0 = all cores
    // Optimal sample allocation (issue 10): the optimal strategies draw a
    // pilot pass with the settings' counts, then split each tile's later
    // passes among the techniques to minimise the optimal estimator's
    // variance per unit time (mis/allocation.h), every technique keeping a
    // floor share. Needs two passes or more: a bake of a sample budget then
    // takes a quarter of its rounds as the pilot. Off by default: it wins at
    // equal samples in most hard cases but not at equal time (the choice and
    // the costlier draws it favours; bench/results/hard_cases_allocation_gain.txt).
    bool allocate_samples = false;
    // Lightmaps: bake only tiles [first_tile, first_tile + tile_count) of the
    // bake's kBakeTile² tiles, in row-major order (tile_count 0: all). Every
    // texel's draws are fixed by its index and the seed, so the texels of a
    // tile range come out with the same bits as in a whole bake; the rest
    // stay 0 (mask 0), and the margin is left to fill_bake_margin once the
    // ranges are put together (a farm bakes ranges on many machines).
    std::size_t first_tile = 0, tile_count = 0;
};

// The side of a bake's square tiles, in texels (lightmaps; vertex bakes take
// kBakeTile² points a tile).
constexpr int kBakeTile = 16;
// How many tiles a lightmap bake of width × height has.
inline std::size_t bake_tile_count(int width, int height) {
    return std::size_t((width + kBakeTile - 1) / kBakeTile) *
           std::size_t((height + kBakeTile - 1) / kBakeTile);
}

struct BakeStats {
    BakeStatus status = BakeStatus::Complete;
    double seconds = 0;
    // samples: the texels' schedules (`samples` = N: N per texel, rounds of
    // the techniques' counts). draws: the directions drawn, all techniques:
    // as many, except that a texel whose centre does not see the middle points
    // of the lights that bring most of its light (shadowed_texels;
    // DirectLightingSettings::shadowed_draws) draws 4× the
    // counts in each of its rounds. rays_traced: every ray, the extra draws'
    // and the shadow probe's included.
    std::uint64_t samples = 0, draws = 0, rays_traced = 0, mis_systems = 0;
    double samples_per_texel = 0;      // mean over covered texels
    double draws_per_texel = 0;        // mean over covered texels
    std::size_t shadowed_texels = 0;
    // Covered texels (corners, in vertex bakes) whose centre lies inside
    // other geometry (rays from it meet back faces first) or on a face of
    // another mesh turned its way (coinciding surfaces): dark, as Cycles
    // bakes them, and worth an artist's look (overlapping props; issue 32).
    std::size_t buried_texels = 0;
    double mean_relative_error = 0;    // estimated standard error / value, covered texels
    double max_relative_error = 0;
    int passes = 0;                    // passes started
    double passes_per_texel = 0;       // mean; fewer where the noise target was met
    std::size_t texels = 0, covered = 0, degenerate_uv_triangles = 0, overlapping_texels = 0;
    std::string plan;                  // EffectPlan::to_string()
    std::vector<std::string> techniques;
    std::vector<int> samples_per_round;
    // Sample allocation: what it did (empty when off), and each technique's
    // mean share of the allocated passes' samples over the tiles.
    std::string allocation;
    std::vector<double> allocated_shares;
    // After each completed pass: samples, sampling time and mean relative
    // error so far; and from them what halving that error would cost.
    std::vector<BakePassRecord> convergence;
    HalvingPrediction halving;
};

struct BakeResult {
    int width = 0, height = 0;  // lightmap; vertices/corners: count × 1
    std::vector<float> value;   // width·height·3, E/π, row 0 at the bottom
    std::vector<float> noise;   // width·height, estimated relative standard error
    std::vector<float> mask;    // width·height, 1 where baked, 0 margin or empty
    std::vector<std::uint32_t> samples;  // width·height, samples taken (0 off the islands)
    BakeStats stats;
};

// fraction in [0, 1]; may be called from any thread; returning false cancels.
using BakeProgress = std::function<bool(double)>;

// Throws std::invalid_argument for unusable input (no UVs, bad size, a mesh
// id out of range, ...). A cancelled bake returns with status Cancelled.
BakeResult bake(const Scene& scene, const BakeSettings& settings,
                const BakeProgress& progress = nullptr);

// A lightmap put together from tile ranges' values and noise (each texel
// from the range that baked it), width·height·3 and width·height: fills the
// margin around the UV islands of settings' mesh as a whole bake does.
void fill_bake_margin(const Scene& scene, const BakeSettings& settings, float* value,
                      float* noise);

}  // namespace omis
