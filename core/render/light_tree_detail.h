// What the light selector's build and its walk share (internal to
// light_selection.cpp and light_tree_walk.cpp): when a node is a cluster, and
// float rounding that keeps bounds conservative.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

namespace omis {

// A tree node is a cluster at a receiver — its lights drawn ∝ power, no
// longer ∝ the importance of its children — where its bounding sphere
// subtends less than asin(kClusterSine) from the receiver and its normal
// cone is narrower than acos(kClusterCone): the importance of its lights
// then differs by about ±2·kClusterSine in distance and by the spread of
// their normals, so a draw by power costs a little variance (bench/results/
// emitters.txt) and takes a binary search in place of the walk down the
// rest of the tree — the walk's length then grows with the angular size of
// the lights, not with their number.
constexpr double kClusterSine = 0.1;
constexpr double kClusterCone = 0.7;

// The float next to f, toward zero (down) or away from it (up), for f > 0:
// the neighbours of a positive float are its bit pattern ∓ 1 (+∞'s lower
// neighbour is FLT_MAX). std::nextafter's library call was ~7 % of an
// importance evaluation (round_up of a region's radius at every one).
inline float next_down_positive(float f) {
    std::uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    --bits;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}
inline float next_up_positive(float f) {
    std::uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    ++bits;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

inline float round_down(double v) {
    float f = float(v);
    if (!(double(f) > v)) return f;
    return f > 0 ? next_down_positive(f) : std::nextafter(f, -INFINITY);
}
inline float round_up(double v) {
    float f = float(v);
    if (!(double(f) < v)) return f;
    return f > 0 && f < INFINITY ? next_up_positive(f) : std::nextafter(f, INFINITY);
}

}  // namespace omis
