#include "bake/bake_layout.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "bake/bake_points.h"

namespace omis::bake_detail {

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

BakeLayout::BakeLayout(const Mesh& mesh, const BakeSettings& settings) : target(settings.target) {
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

// Covered texels (corners) whose centre lies inside other geometry, or on a
// face of another mesh turned its way (BakeStats::buried_texels). Only points
// in another mesh's bounds trace, but for contacts (one ray where they are not
// inside).
std::size_t count_buried(const Scene& scene, const BakeLayout& layout, const Mesh& mesh,
                         bool smooth_normals, const SurfaceContacts& contacts) {
    const GeometryScene& geometry = scene.geometry();
    std::atomic<std::size_t> buried{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, layout.count, 256),
                      [&](const tbb::blocked_range<std::size_t>& range) {
        std::size_t here = 0;
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            if (!layout.covered(i)) continue;
            SurfacePoint p;
            std::uint32_t t;
            if (layout.lightmap()) {
                p = TexelFootprint(mesh, layout.coverage, i, smooth_normals).centre();
                t = layout.coverage.triangle[i];
            } else {  // before on_contact moves them
                t = std::uint32_t(i / 3);
                p = layout.points[i];
            }
            here += contacts.on_other_surface(t, p.x) == SurfaceContacts::Contact::Facing ||
                    (contacts.may_be_inside(p.x) && inside_other_geometry(geometry, p.x, p.n, p.ng));
        }
        buried.fetch_add(here, std::memory_order_relaxed);
    });
    return buried.load();
}

}  // namespace omis::bake_detail
