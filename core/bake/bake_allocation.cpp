#include "bake/bake_allocation.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "bake/baker.h"
#include "mis/allocation.h"

namespace omis::bake_detail {

Pass Baker::shade_tile(PointLighting& shader, std::size_t tile, const Pass& pass,
                       std::vector<Shaded>& out) {
    if (!allocate_) {
        layout_.tile_points(tile, [&](std::size_t i) { shade_point(shader, i, pass, out); });
        return pass;
    }
    TileAllocation& t = allocation_.tile(tile);
    if (t.shares.empty()) {
        pilot_tile(shader, tile, pass, out);
        return pass;
    }
    Pass allocated = allocation_.allocated_pass(t, pass);
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
    allocation_.end_pilot(tile, pilot, counts, pass);
}

void SampleAllocation::end_pilot(std::size_t tile, const AllocationPilot& pilot,
                                 const std::vector<int>& counts, const Pass& pass) {
    TileAllocation& t = tiles_[tile];
    t.shares.assign(counts.begin(), counts.end());  // the pilot's own split
    if (pilot.rounds() > 0 && pilot.samples() > 0) {
        const double floor =
            std::min(kAllocationFloor, 0.5 / double(techniques_));
        t.shares = optimal_shares(pilot, pilot.cost(), floor);
    }
    t.drawn.push_back({pass.first_round, pass.rounds, pass.counts});
    t.next_round = pass.first_round + pass.rounds;
}

// A later pass of an allocated tile: the pass's samples per texel in rounds
// of the tile's shares — as many rounds as keep at least kMinAllocatedRound
// samples each, kRoundPerTechnique a technique (a pass's last partial round:
// one round).
Pass SampleAllocation::allocated_pass(TileAllocation& t, const Pass& pass) {
    const int P = per_round_;
    const int least = std::max<int>(kMinAllocatedRound,
                                    kRoundPerTechnique * int(techniques_));
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
void SampleAllocation::describe(BakeStats& stats, const DirectLightingSettings& lighting) const {
    const std::size_t T = lighting.techniques.size();
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
        s << "; " << lighting.techniques[k].name() << " " << sum[k] / n << " ("
          << lo[k] << "–" << hi[k] << ")";
    }
    stats.allocation = s.str();
}

}  // namespace omis::bake_detail
