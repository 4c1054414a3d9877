// The randomized low-discrepancy sequence: stratification of 2-D pairs and
// 1-D dimensions, uniformity of each point over randomizations, decorrelation
// between dimension groups, unbiased integration.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <vector>

#include "sampling/sequence.h"

using namespace omis;

namespace {

// Every elementary interval of area 2^-m holds exactly one of the 2^m points
// (a (0,m,2)-net), for every split 2^a × 2^(m−a).
bool is_net(const std::vector<double>& u, const std::vector<double>& v, int m) {
    const std::size_t n = std::size_t(1) << m;
    for (int a = 0; a <= m; ++a) {
        std::vector<int> count(n, 0);
        for (std::size_t i = 0; i < n; ++i) {
            const std::size_t x = std::size_t(u[i] * double(1u << a));
            const std::size_t y = std::size_t(v[i] * double(1u << (m - a)));
            ++count[(x << (m - a)) | y];
        }
        for (int c : count)
            if (c != 1) return false;
    }
    return true;
}

}  // namespace

TEST_CASE("sequence: unscrambled Sobol' pairs are nets of quality zero (every elementary interval holds one point)", "[sequence]") {
    for (int m = 1; m <= 10; ++m) {
        std::vector<double> u, v;
        for (std::uint32_t i = 0; i < (1u << m); ++i) {
            u.push_back(sobol_dim0(i) * 0x1.0p-32);
            v.push_back(sobol_dim1(i) * 0x1.0p-32);
        }
        CHECK(is_net(u, v, m));
    }
}

TEST_CASE("sequence: scrambled pairs stay nets in every aligned block (passes continue)",
          "[sequence]") {
    for (std::uint64_t seed : {1ull, 77ull, 123456789ull}) {
        const ScrambledSobol s(seed);
        for (std::uint32_t group : {0u, 2u, 5u})
            for (int m : {2, 5, 8})
                for (std::uint32_t block : {0u, 1u, 3u}) {
                    std::vector<double> u, v;
                    const std::uint32_t n = 1u << m;
                    for (std::uint32_t i = block * n; i < (block + 1) * n; ++i) {
                        double a, b;
                        s.get_2d(i, group, a, b);
                        u.push_back(a);
                        v.push_back(b);
                    }
                    INFO("seed " << seed << " group " << group << " m " << m << " block "
                                 << block);
                    CHECK(is_net(u, v, m));
                    // 1-D: one point per interval of width 2^-m.
                    std::vector<int> count(n, 0);
                    for (std::uint32_t i = block * n; i < (block + 1) * n; ++i)
                        ++count[std::size_t(s.get_1d(i, group + 1) * n)];
                    for (int c : count) CHECK(c == 1);
                }
    }
}

TEST_CASE("sequence: each point is uniform over randomizations", "[sequence]") {
    // For fixed indices, 4096 seeds put u into 16 bins; each bin's count is
    // Binomial(4096, 1/16): mean 256, σ ≈ 15.5. 5σ per bin keeps the chance of
    // a false failure over all 16·4·3 bins below 1e-4.
    const int seeds = 4096, bins = 16;
    for (std::uint32_t index : {0u, 1u, 7u, 1000u}) {
        std::vector<int> cu(bins, 0), cv(bins, 0), c1(bins, 0);
        for (int k = 0; k < seeds; ++k) {
            const ScrambledSobol s(std::uint64_t(k) * 2654435761ull + 17);
            double u, v;
            s.get_2d(index, 3, u, v);
            ++cu[int(u * bins)];
            ++cv[int(v * bins)];
            ++c1[int(s.get_1d(index, 4) * bins)];
        }
        const double mean = double(seeds) / bins, sigma = std::sqrt(mean * (1 - 1.0 / bins));
        for (int b = 0; b < bins; ++b) {
            INFO("index " << index << " bin " << b);
            CHECK(std::abs(cu[b] - mean) < 5 * sigma);
            CHECK(std::abs(cv[b] - mean) < 5 * sigma);
            CHECK(std::abs(c1[b] - mean) < 5 * sigma);
        }
    }
}

TEST_CASE("sequence: dimension groups are decorrelated", "[sequence]") {
    // Sample correlation between the selection dimension (group 1) and the
    // shape pair (group 2) over 4096 points: for independent uniforms its
    // standard deviation is 1/√4096 = 0.0156; require < 5σ.
    const ScrambledSobol s(99);
    const int n = 4096;
    double su = 0, sv = 0, suu = 0, svv = 0, suv = 0;
    for (int i = 0; i < n; ++i) {
        const double a = s.get_1d(i, 1);
        double b, c;
        s.get_2d(i, 2, b, c);
        su += a;
        sv += b;
        suu += a * a;
        svv += b * b;
        suv += a * b;
    }
    const double cov = suv / n - su / n * sv / n;
    const double corr = cov / std::sqrt((suu / n - su * su / n / n) * (svv / n - sv * sv / n / n));
    CHECK(std::abs(corr) < 5.0 / std::sqrt(double(n)));
}

TEST_CASE("sequence: integration is unbiased and beats independent draws", "[sequence]") {
    // The quarter disk's area π/4 from 64 points, over 2000 randomizations.
    // Unbiased: the mean of the estimates lies within 4 standard errors of π/4.
    // Stratified: the variance is far below independent draws' (π/4)(1−π/4)/64.
    const int runs = 2000, n = 64;
    double sum = 0, sum2 = 0;
    for (int r = 0; r < runs; ++r) {
        const ScrambledSobol s(std::uint64_t(r) + 1000);
        int inside = 0;
        for (int i = 0; i < n; ++i) {
            double u, v;
            s.get_2d(i, 0, u, v);
            inside += u * u + v * v < 1;
        }
        const double e = double(inside) / n;
        sum += e;
        sum2 += e * e;
    }
    const double mean = sum / runs, var = sum2 / runs - mean * mean;
    const double exact = std::atan(1.0);
    CHECK(std::abs(mean - exact) < 4 * std::sqrt(var / runs));
    CHECK(var < 0.25 * exact * (1 - exact) / n);
}

namespace {

// Every elementary box of volume 2^(t−m) in [0,1)^4 holds exactly 2^t of the
// 2^m points (a (t,m,4)-net), for every split of m − t into four exponents.
bool is_net_4d(const std::vector<std::array<double, 4>>& p, int m, int t) {
    const int k = m - t;
    for (int a = 0; a <= k; ++a)
        for (int b = 0; a + b <= k; ++b)
            for (int c = 0; a + b + c <= k; ++c) {
                const int d = k - a - b - c;
                std::vector<int> count(std::size_t(1) << k, 0);
                for (const auto& x : p) {
                    const std::size_t i0 = std::size_t(x[0] * double(1u << a));
                    const std::size_t i1 = std::size_t(x[1] * double(1u << b));
                    const std::size_t i2 = std::size_t(x[2] * double(1u << c));
                    const std::size_t i3 = std::size_t(x[3] * double(1u << d));
                    ++count[((i0 << b | i1) << c | i2) << d | i3];
                }
                for (int n : count)
                    if (n != 1 << t) return false;
            }
    return true;
}

}  // namespace

TEST_CASE("sequence: 4-D points are (3,m,4)-nets in every aligned block, their first pair a (0,2)-net",
          "[sequence]") {
    // Sobol' dimensions 0–3 (primitive polynomials of degrees 1, 1, 2, 3) form
    // a (t,m,4)-net with t = Σ (degree − 1) = 3; the nested scrambles keep it.
    // Unscrambled first: the direction numbers themselves.
    for (int m = 3; m <= 9; ++m) {
        std::vector<std::array<double, 4>> p;
        for (std::uint32_t i = 0; i < (1u << m); ++i)
            p.push_back({sobol_dim0(i) * 0x1.0p-32, sobol_dim1(i) * 0x1.0p-32,
                         sobol_dim2(i) * 0x1.0p-32, sobol_dim3(i) * 0x1.0p-32});
        INFO("unscrambled, m " << m);
        CHECK(is_net_4d(p, m, 3));
    }
    for (std::uint64_t seed : {3ull, 99ull}) {
        const ScrambledSobol s(seed);
        for (int m : {4, 8})
            for (std::uint32_t block : {0u, 1u, 5u}) {
                const std::uint32_t n = 1u << m;
                std::vector<std::array<double, 4>> p;
                std::vector<double> u, v;
                for (std::uint32_t i = block * n; i < (block + 1) * n; ++i) {
                    std::array<double, 4> x;
                    s.get_4d(i, 0, x.data());
                    p.push_back(x);
                    u.push_back(x[0]);
                    v.push_back(x[1]);
                }
                INFO("seed " << seed << " m " << m << " block " << block);
                CHECK(is_net_4d(p, m, 3));
                CHECK(is_net(u, v, m));
            }
    }
}

TEST_CASE("sequence: 4-D points are uniform over randomizations", "[sequence]") {
    // As for the pairs: 4096 seeds, 16 bins per coordinate, Binomial(4096,
    // 1/16) counts (σ ≈ 15.5), 5σ per bin: a false failure over 16·4·3 bins
    // below 1e-4.
    const int seeds = 4096, bins = 16;
    for (std::uint32_t index : {0u, 5u, 1000u}) {
        std::vector<std::array<int, 4>> count(bins, {0, 0, 0, 0});
        for (int k = 0; k < seeds; ++k) {
            const ScrambledSobol s(std::uint64_t(k) * 2654435761ull + 5);
            double x[4];
            s.get_4d(index, 1, x);
            for (int d = 0; d < 4; ++d) ++count[int(x[d] * bins)][d];
        }
        const double mean = double(seeds) / bins, sigma = std::sqrt(mean * (1 - 1.0 / bins));
        for (int b = 0; b < bins; ++b)
            for (int d = 0; d < 4; ++d) {
                INFO("index " << index << " bin " << b << " dimension " << d);
                CHECK(std::abs(count[b][d] - mean) < 5 * sigma);
            }
    }
}
