#include "sampling/sequence.h"

#include "math/random.h"

namespace omis {
namespace {

std::uint32_t reverse_bits(std::uint32_t x) {
    x = (x << 16) | (x >> 16);
    x = ((x & 0x00ff00ffu) << 8) | ((x & 0xff00ff00u) >> 8);
    x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
    x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
    x = ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
    return x;
}

// Laine–Karras style hash: bit j of the result depends only on bits ≤ j of x
// (multiplication and addition carry upward), with Burley's constants. Used
// on bit-reversed values, it flips each bit by a function of the more
// significant ones: a nested uniform (Owen) scramble.
std::uint32_t laine_karras(std::uint32_t x, std::uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

std::uint32_t group_seed(std::uint64_t seed, std::uint32_t group, std::uint32_t salt) {
    return std::uint32_t(mix64(seed ^ mix64((std::uint64_t(group) << 8) | salt)));
}

double to_unit(std::uint32_t x) { return x * 0x1.0p-32; }

}  // namespace

std::uint32_t sobol_dim0(std::uint32_t index) { return reverse_bits(index); }

std::uint32_t sobol_dim1(std::uint32_t index) {
    // Direction numbers of primitive polynomial x + 1: v_0 = 2^31,
    // v_i = v_{i-1} ^ (v_{i-1} >> 1).
    std::uint32_t x = 0, v = 0x80000000u;
    for (; index; index >>= 1, v ^= v >> 1)
        if (index & 1) x ^= v;
    return x;
}

std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed) {
    return reverse_bits(laine_karras(reverse_bits(x), seed));
}

ScrambledSobol::ScrambledSobol(std::uint64_t seed) : seed_(seed) {
    for (std::uint32_t g = 0; g < kCachedGroups; ++g)
        for (std::uint32_t salt = 0; salt < 3; ++salt) cached_[g][salt] = group_seed(seed, g, salt);
}

std::uint32_t ScrambledSobol::seed(std::uint32_t group, std::uint32_t salt) const {
    return group < kCachedGroups ? cached_[group][salt] : group_seed(seed_, group, salt);
}

double ScrambledSobol::get_1d(std::uint32_t index, std::uint32_t group) const {
    // Shuffling the index by a nested scramble keeps aligned power-of-two
    // blocks together, so prefixes stay stratified.
    const std::uint32_t i = owen_scramble(index, seed(group, 0));
    return to_unit(owen_scramble(sobol_dim0(i), seed(group, 1)));
}

void ScrambledSobol::get_2d(std::uint32_t index, std::uint32_t group, double& u,
                            double& v) const {
    const std::uint32_t i = owen_scramble(index, seed(group, 0));
    u = to_unit(owen_scramble(sobol_dim0(i), seed(group, 1)));
    v = to_unit(owen_scramble(sobol_dim1(i), seed(group, 2)));
}

}  // namespace omis
