// Sample allocation's state per tile (BakeSettings::allocate_samples).
#pragma once

#include <cstddef>
#include <deque>
#include <vector>

#include "bake/bake.h"
#include "bake/bake_means.h"
#include "mis/allocation.h"
#include "render/direct_lighting.h"

namespace omis::bake_detail {

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

// The tiles' shares and calls of a bake that allocates its samples.
class SampleAllocation {
public:
    // techniques: how many take part (LightingContext::techniques).
    void start(std::size_t tiles, int per_round, std::size_t techniques) {
        tiles_.resize(tiles);
        per_round_ = per_round;
        techniques_ = techniques;
    }
    TileAllocation& tile(std::size_t i) { return tiles_[i]; }
    // A tile's pilot pass ran: its shares, from what the pilot recorded.
    void end_pilot(std::size_t tile, const AllocationPilot& pilot, const std::vector<int>& counts,
                   const Pass& pass);
    Pass allocated_pass(TileAllocation& t, const Pass& pass);
    // What the allocation did, into stats (BakeStats::allocation).
    void describe(BakeStats& stats, const DirectLightingSettings& lighting) const;

private:
    std::vector<TileAllocation> tiles_;
    int per_round_ = 0;
    std::size_t techniques_ = 0;
};

}  // namespace omis::bake_detail
