// The per-sample shortcuts of the hot path against the definitions they
// replace: Sobol's second dimension by byte tables against its direction-
// number loop, and the cosine warp's corner nodes in closed form against the
// directions the shapes' own samplers reach at the square's corners.
#include <catch2/catch.hpp>

#include <cstdint>
#include <random>

#include "sampling/cosine_warp.h"
#include "sampling/sequence.h"
#include "sampling/spherical.h"

using namespace omis;

namespace {

// The definition: the XOR of the direction numbers of the index's set bits
// (primitive polynomial x + 1: v_0 = 2^31, v_i = v_{i-1} ^ (v_{i-1} >> 1)).
std::uint32_t sobol_dim1_by_bits(std::uint32_t index) {
    std::uint32_t x = 0, v = 0x80000000u;
    for (; index; index >>= 1, v ^= v >> 1)
        if (index & 1) x ^= v;
    return x;
}

}  // namespace

TEST_CASE("hot path: Sobol' second dimension by tables equals the direction-number loop",
          "[sequence][hot-path]") {
    std::mt19937 rng(5);
    for (std::uint32_t i = 0; i < 4096; ++i) CHECK(sobol_dim1(i) == sobol_dim1_by_bits(i));
    // Shuffled indices carry high bits: every byte's table is exercised.
    for (int k = 0; k < 100000; ++k) {
        const std::uint32_t i = rng();
        REQUIRE(sobol_dim1(i) == sobol_dim1_by_bits(i));
    }
    CHECK(sobol_dim1(0xffffffffu) == sobol_dim1_by_bits(0xffffffffu));
}

TEST_CASE("hot path: spherical shapes map the square's corners to their own corners",
          "[sampling][hot-path]") {
    // Receivers below, beside and just above the plane of each shape. The
    // samplers solve for the corner (Newton, arcs); agreement to 1e-12 in
    // direction is the solvers' own accuracy, not a tolerance of the shortcut.
    const Vec3 points[] = {{0, 0, 0}, {0.9, -0.3, 0.6}, {3, 2, 0.99}, {-0.2, 0.1, 1e-4}};
    for (const Vec3& x : points) {
        const auto rect = SphericalRect::make(x, {-0.3, -0.2, 1}, {0.6, 0, 0}, {0, 0.5, 0});
        const auto tri =
            SphericalTriangle::make(x, {-0.4, -0.3, 1}, {0.5, -0.2, 1}, {0.1, 0.6, 1});
        REQUIRE(rect);
        REQUIRE(tri);
        for (int j = 0; j <= 1; ++j)
            for (int i = 0; i <= 1; ++i) {
                INFO("x " << x.x << " " << x.y << " " << x.z << " corner " << i << j);
                CHECK(length(rect->corner_direction(i, j) - rect->sample(i, j).dir) < 1e-12);
                CHECK(length(tri->corner_direction(i, j) - tri->sample(i, j).dir) < 1e-12);
            }
    }
}
