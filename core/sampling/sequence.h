// One randomized low-discrepancy sequence for every dimension of a sample:
// Owen-scrambled Sobol' points (Burley 2020, "Practical Hash-based Owen
// Scrambling"), drawn as independent 2-D (0,2)-sequence pairs and 1-D
// van der Corput dimensions ("padding", as pbrt-v4's PaddedSobolSampler).
//
// Each dimension group (footprint position, light selection, light shape /
// BSDF direction) hashes its own scramble seed and shuffles the sample index
// with its own seed, so groups are decorrelated from each other while each
// keeps its stratification: any 2^m consecutive indices from a multiple of
// 2^m form a (0,m,2)-net per pair, and every point is uniform on [0,1)^d, so
// estimates stay unbiased.
#pragma once

#include <cstdint>

namespace omis {

// Seeds for one stream of samples (one texel and technique and randomization).
// The scramble seeds of a group are hashed at its first use and kept: a bake
// makes a texel's sequences again at every pass and, in a one-round pass,
// draws a point or two from each, using few of its groups (hashing every
// group's seeds up front was ~11 % of what a later pass repeats). Keeping
// them writes the object in const calls: one object is for one thread.
class ScrambledSobol {
public:
    explicit ScrambledSobol(std::uint64_t seed);

    // Dimension group `group` (any small integer) of sample `index`.
    double get_1d(std::uint32_t index, std::uint32_t group) const;
    void get_2d(std::uint32_t index, std::uint32_t group, double& u, double& v) const;
    // Four dimensions of one point of the Sobol' sequence (dimensions 0–3 at
    // one shuffled index): out[0..1] are get_2d's (0,2)-net pair, out[2..3]
    // stratified jointly with them — the pair that varies with the first
    // (e.g. a footprint position beside a light point) is then not paired at
    // random.
    void get_4d(std::uint32_t index, std::uint32_t group, double out[4]) const;

private:
    // Seeds kept for the first groups, of every salt get_4d uses.
    static constexpr std::uint32_t kCachedGroups = 4, kSalts = 5;
    std::uint32_t seed(std::uint32_t group, std::uint32_t salt) const {
        if (group < kCachedGroups && (ready_ >> (group * kSalts + salt) & 1))
            return cached_[group][salt];
        return first_seed(group, salt);
    }
    std::uint32_t first_seed(std::uint32_t group, std::uint32_t salt) const;
    std::uint64_t seed_;
    mutable std::uint32_t ready_ = 0;  // bit group · kSalts + salt: cached_ holds it
    mutable std::uint32_t cached_[kCachedGroups][kSalts];
};

// The building blocks, exposed for tests.
std::uint32_t sobol_dim0(std::uint32_t index);  // bit reversal (van der Corput)
std::uint32_t sobol_dim1(std::uint32_t index);  // Sobol' second dimension
std::uint32_t sobol_dim2(std::uint32_t index);  // third
std::uint32_t sobol_dim3(std::uint32_t index);  // fourth
// Nested uniform scramble of a 32-bit fixed-point coordinate (Owen): each bit
// is flipped by a hash of the bits above it.
std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed);

}  // namespace omis
