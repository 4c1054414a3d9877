// Per-point random streams: PCG32 (O'Neill 2014), seeded by hashing the
// user's seed with the point's index, so results do not depend on which
// thread handles which point.
#pragma once

#include <cstdint>

namespace omis {

// SplitMix64 finaliser: decorrelates nearby integers into seeds.
inline std::uint64_t mix64(std::uint64_t z) {
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

class Pcg32 {
public:
    Pcg32(std::uint64_t seed, std::uint64_t stream) {
        inc_ = (stream << 1u) | 1u;
        next_u32();
        state_ += seed;
        next_u32();
    }

    std::uint32_t next_u32() {
        const std::uint64_t old = state_;
        state_ = old * 6364136223846793005ull + inc_;
        const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
        const auto rot = static_cast<std::uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
    }

    // Uniform in [0, 1) with 53 random bits.
    double next_double() {
        const std::uint64_t hi = next_u32(), lo = next_u32();
        return double(((hi << 32) | lo) >> 11) * 0x1.0p-53;
    }

private:
    std::uint64_t state_ = 0, inc_ = 0;
};

// The stream of point `index` for a user seed.
inline Pcg32 point_stream(std::uint64_t seed, std::uint64_t index) {
    return Pcg32(mix64(seed ^ mix64(index)), mix64(index + 0x632be59bd9b4e019ull));
}

}  // namespace omis
