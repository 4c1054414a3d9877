// A bake's input checked, its sample budget split into rounds, and its
// layout: which points it shades (texels or corners) and in which tiles.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "bake/bake.h"
#include "bake/uv_raster.h"
#include "render/direct_lighting.h"
#include "scene/surface_contacts.h"

namespace omis::bake_detail {

// Texels are processed in square tiles: neighbours share cache lines and
// lights' per-point work, and a tile is the unit of progress and cancel.
constexpr int kTile = kBakeTile;

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

SampleBudget plan_samples(const LightingContext& context, long long samples, int rounds);

// Throws for unusable input (bake.h: bake).
void validate(const Scene& scene, const BakeSettings& in);

// Where to shade: a lightmap's texels (those inside the UV layout are covered)
// or a mesh's triangle corners, visited in tiles.
struct BakeLayout {
    BakeLayout(const Mesh& mesh, const BakeSettings& settings);
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

// The key a bake's measured pass cost is kept under in its Scene: what sets
// the cost of a round (the mesh and its points, the techniques and their
// counts, the streams, the threads), not the strategy (which costs per pass,
// not per round) nor the budget.
std::uint64_t bake_shape(const BakeSettings& s, const BakeLayout& layout);

// How many covered points lie inside other geometry or on another mesh's face
// turned their way (BakeStats::buried_texels); corners before on_contact
// moves them.
std::size_t count_buried(const Scene& scene, const BakeLayout& layout, const Mesh& mesh,
                         bool smooth_normals, const SurfaceContacts& contacts);

}  // namespace omis::bake_detail
