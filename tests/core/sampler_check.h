// The sampler checker shared by the sampling tests (test_sampling.cpp, one shape
// sampler at a time) and the light tests (test_lights.cpp, through the light
// dispatch): the four checks per sampler of STYLE.md, and Pearson's chi-square
// with the p-value from the regularised incomplete gamma function.
#pragma once

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "math/vec3.h"
#include "sampling/shapes.h"

namespace omis::testing {

constexpr int kSamples = 50000;
// Each chi-square test is run at significance α = 1e-4. About 150 tests run (here and
// in test_lights.cpp), so the family-wise level (Šidák) is 1 − (1 − 1e-4)^150 ≈ 1.5%:
// a failure is worth a look.
constexpr double kAlpha = 1e-4;

// Regularised upper incomplete gamma Q(a, x): series below a + 1, Lentz continued
// fraction above (the textbook split).
inline double gamma_q(double a, double x) {
    if (x <= 0) return 1.0;
    const double lg = -x + a * std::log(x) - std::lgamma(a);
    if (x < a + 1) {
        double ap = a, del = 1.0 / a, sum = del;
        for (int i = 0; i < 10000 && std::abs(del) > 1e-16 * std::abs(sum); ++i) {
            ap += 1;
            del *= x / ap;
            sum += del;
        }
        return std::max(0.0, 1.0 - sum * std::exp(lg));
    }
    const double tiny = 1e-300;
    double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 10000; ++i) {
        const double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::abs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1) < 1e-16) break;
    }
    return std::exp(lg) * h;
}

// p-value of Pearson's chi-square; cells expecting < 5 are pooled into one cell (and
// that one into the largest cell if it still expects < 5).
inline double chi_square_pvalue(const std::vector<double>& observed, const std::vector<double>& expected) {
    std::vector<double> o, e;
    double po = 0, pe = 0;
    for (size_t i = 0; i < observed.size(); ++i) {
        if (expected[i] < 5) {
            po += observed[i];
            pe += expected[i];
        } else {
            o.push_back(observed[i]);
            e.push_back(expected[i]);
        }
    }
    if (pe >= 5 || o.empty()) {
        o.push_back(po);
        e.push_back(pe);
    } else if (po > 0 || pe > 0) {
        size_t big = 0;
        for (size_t i = 1; i < e.size(); ++i)
            if (e[i] > e[big]) big = i;
        o[big] += po;
        e[big] += pe;
    }
    if (o.size() < 2) return 1.0;
    double chi2 = 0;
    for (size_t i = 0; i < o.size(); ++i) {
        if (e[i] <= 0) return o[i] > 0 ? 0.0 : 1.0;
        chi2 += (o[i] - e[i]) * (o[i] - e[i]) / e[i];
    }
    return gamma_q(0.5 * (o.size() - 1), 0.5 * chi2);
}

// A direction sampler and what the four checks need to know about it.
struct SamplerUnderTest {
    std::string name;
    std::function<std::optional<LightSample>(double, double)> sample;
    std::function<double(const Vec3&)> pdf;
    std::function<std::optional<Point2>(const Vec3&)> invert;  // may be empty
    std::function<int(const Vec3&)> bin;                       // cell index, −1 if none
    std::vector<double> cell_prob;                             // exact, per cell
    double measure = 0;     // solid angle of the support (exact formula)
    bool check_mean = true;
    bool finite_dist = true;
    double invert_tol = 1e-6;
    double prob_sum_tol = 1e-6;
    double measure_tol = 1e-8;  // relative error of the reference measure
};

// The four checks of STYLE.md on n draws from (u1, u2) ~ U[0,1)² with this seed:
// every draw finite and binned; pdf() at the draw equals the draw's pdf; inversion
// round-trips; mean of 1/pdf within 4σ of the measure; chi-square of the cells.
inline void run_sampler_check(const SamplerUnderTest& t, uint64_t seed, int n = kSamples) {
    INFO("sampler " << t.name << ", measure " << t.measure);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    int missing = 0, nonfinite = 0, unbinned = 0;
    double worst_pdf = 0, worst_inv = 0, sum = 0, sum2 = 0;
    std::vector<double> counts(t.cell_prob.size(), 0.0);
    for (int i = 0; i < n; ++i) {
        const double u1 = uni(rng), u2 = uni(rng);
        const auto s = t.sample(u1, u2);
        if (!s) {
            ++missing;
            continue;
        }
        const bool finite = isfinite(s->dir) && std::isfinite(s->pdf) && s->pdf > 0 &&
                            s->dist > 0 && (!t.finite_dist || std::isfinite(s->dist)) &&
                            std::abs(length(s->dir) - 1) < 1e-12;
        if (!finite) {
            ++nonfinite;
            continue;
        }
        const double pe = t.pdf(s->dir);
        if (!std::isfinite(pe)) ++nonfinite;
        worst_pdf = std::max(worst_pdf, std::abs(pe - s->pdf) / s->pdf);
        if (t.invert) {
            const auto u = t.invert(s->dir);
            if (u) {
                const double d2 = std::abs(u->y - u2);
                worst_inv = std::max({worst_inv, std::abs(u->x - u1), std::min(d2, 1 - d2)});
            }
        }
        const double r = 1.0 / s->pdf;
        sum += r;
        sum2 += r * r;
        const int b = t.bin(s->dir);
        if (b < 0) ++unbinned;
        else counts[b] += 1;
    }
    CHECK(missing == 0);
    CHECK(nonfinite == 0);
    CHECK(unbinned == 0);
    CHECK(worst_pdf <= 1e-6);
    if (t.invert) CHECK(worst_inv <= t.invert_tol);
    // Mean of 1/pdf estimates the measure of the support. Its standard error σ/√n is
    // estimated from the same samples; the CLT makes the mean ~normal at n = 5e4, so a
    // 4σ band is exceeded with probability 6e-5 per test. The 1e-8 relative floor covers
    // constant pdfs (σ = 0) whose measure is computed by another formula.
    const double mean = sum / n;
    const double var = std::max(0.0, (sum2 / n - mean * mean) * n / (n - 1.0));
    const double se = std::sqrt(var / n);
    if (t.check_mean) CHECK(std::abs(mean - t.measure) <= 4 * se + t.measure_tol * t.measure);
    double psum = 0;
    std::vector<double> expected(t.cell_prob.size());
    for (size_t i = 0; i < expected.size(); ++i) {
        psum += t.cell_prob[i];
        expected[i] = t.cell_prob[i] * n;
    }
    CHECK(std::abs(psum - 1) <= t.prob_sum_tol);
    const double p = chi_square_pvalue(counts, expected);
    INFO("chi-square p-value " << p);
    CHECK(p >= kAlpha);
}

}  // namespace omis::testing
