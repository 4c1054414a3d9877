#include "sampling/sequence.h"

#include "math/random.h"

namespace omis {
namespace {

constexpr std::uint32_t reverse_bits(std::uint32_t x) {
    x = __builtin_bswap32(x);  // the bytes; then the bits within them
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

// A Sobol' dimension as a GF(2)-linear map, one 256-entry table per byte of
// the index: four lookups instead of a loop over up to 32 bits (the shuffled
// indices have high bits set). Direction numbers v_i = m_i · 2^(31−i) from the
// primitive polynomial of degree s with inner coefficients a and initial m
// (Joe & Kuo's new-joe-kuo-6.21201, dimensions 2–4):
//   m_i = m_{i−s} ⊕ 2^s m_{i−s} ⊕ ⊕_{k=1}^{s−1} 2^k a_k m_{i−k}.
struct SobolTables {
    std::uint32_t byte[4][256] = {};
    // reversed: each entry bit-reversed, so the table gives reverse_bits of the
    // dimension (reversal is linear over XOR), which owen_scramble starts with.
    constexpr SobolTables(int s, std::uint32_t a, std::uint32_t m0, std::uint32_t m1,
                          std::uint32_t m2, bool reversed = false) {
        std::uint32_t m[32] = {m0, m1, m2};
        for (int i = s; i < 32; ++i) {
            std::uint32_t next = m[i - s] ^ (m[i - s] << s);
            for (int k = 1; k < s; ++k)
                if (a >> (s - 1 - k) & 1) next ^= m[i - k] << k;
            m[i] = next;
        }
        std::uint32_t v[32] = {};
        for (int i = 0; i < 32; ++i) v[i] = m[i] << (31 - i);
        for (int b = 0; b < 4; ++b)
            for (std::uint32_t x = 0; x < 256; ++x) {
                std::uint32_t r = 0;
                for (int i = 0; i < 8; ++i)
                    if (x >> i & 1) r ^= v[8 * b + i];
                byte[b][x] = reversed ? reverse_bits(r) : r;
            }
    }
    constexpr std::uint32_t operator()(std::uint32_t i) const {
        return byte[0][i & 0xff] ^ byte[1][i >> 8 & 0xff] ^ byte[2][i >> 16 & 0xff] ^
               byte[3][i >> 24];
    }
};
// Built at compile time: x + 1; x² + x + 1; x³ + x + 1.
constexpr SobolTables kDim1(1, 0, 1, 0, 0);
constexpr SobolTables kDim2(2, 1, 1, 3, 0);
constexpr SobolTables kDim3(3, 1, 1, 3, 1);
constexpr SobolTables kDim1Reversed(1, 0, 1, 0, 0, true);
constexpr SobolTables kDim2Reversed(2, 1, 1, 3, 0, true);
constexpr SobolTables kDim3Reversed(3, 1, 1, 3, 1, true);

// owen_scramble(x, seed) given reverse_bits(x).
inline std::uint32_t scramble_reversed(std::uint32_t reversed_x, std::uint32_t seed) {
    return reverse_bits(laine_karras(reversed_x, seed));
}

// owen_scramble, inline in the draws (a sample takes ~8 of them).
inline std::uint32_t scramble(std::uint32_t x, std::uint32_t seed) {
    return scramble_reversed(reverse_bits(x), seed);
}

// owen_scramble(sobol_dim0(i), seed): the reversals cancel.
std::uint32_t scrambled_dim0(std::uint32_t i, std::uint32_t seed) {
    return reverse_bits(laine_karras(i, seed));
}

}  // namespace

std::uint32_t sobol_dim0(std::uint32_t index) { return reverse_bits(index); }

std::uint32_t sobol_dim1(std::uint32_t index) { return kDim1(index); }
std::uint32_t sobol_dim2(std::uint32_t index) { return kDim2(index); }
std::uint32_t sobol_dim3(std::uint32_t index) { return kDim3(index); }

std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed) { return scramble(x, seed); }

ScrambledSobol::ScrambledSobol(std::uint64_t seed) : seed_(seed) {}

std::uint32_t ScrambledSobol::first_seed(std::uint32_t group, std::uint32_t salt) const {
    const std::uint32_t s = group_seed(seed_, group, salt);
    if (group < kCachedGroups) {
        cached_[group][salt] = s;
        ready_ |= 1u << (group * kSalts + salt);
    }
    return s;
}

double ScrambledSobol::get_1d(std::uint32_t index, std::uint32_t group) const {
    // Shuffling the index by a nested scramble keeps aligned power-of-two
    // blocks together, so prefixes stay stratified.
    const std::uint32_t i = scramble(index, seed(group, 0));
    return to_unit(scrambled_dim0(i, seed(group, 1)));
}

void ScrambledSobol::get_2d(std::uint32_t index, std::uint32_t group, double& u,
                            double& v) const {
    const std::uint32_t i = scramble(index, seed(group, 0));
    u = to_unit(scrambled_dim0(i, seed(group, 1)));
    v = to_unit(scramble_reversed(kDim1Reversed(i), seed(group, 2)));
}

void ScrambledSobol::get_4d(std::uint32_t index, std::uint32_t group, double out[4]) const {
    const std::uint32_t i = scramble(index, seed(group, 0));
    out[0] = to_unit(scrambled_dim0(i, seed(group, 1)));
    out[1] = to_unit(scramble_reversed(kDim1Reversed(i), seed(group, 2)));
    out[2] = to_unit(scramble_reversed(kDim2Reversed(i), seed(group, 3)));
    out[3] = to_unit(scramble_reversed(kDim3Reversed(i), seed(group, 4)));
}

}  // namespace omis
