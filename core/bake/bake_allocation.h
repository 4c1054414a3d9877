// Sample allocation's state per tile (BakeSettings::allocate_samples).
#pragma once

#include <deque>
#include <vector>

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

}  // namespace omis::bake_detail
