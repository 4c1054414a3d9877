// Tests of the MIS estimators on 1-D problems with exact answers (SPEC §1–§2).
//
// Statistical checks compare an average over T independent, seeded estimates
// with an exact value; the bound is k = 4 standard errors of that average,
// the standard error itself measured from the T estimates. For a normal
// average a 4σ miss has probability 6e-5 per check, and with fixed seeds a
// pass is reproducible, so the bound is not a tolerance tuned to the data.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "mis/estimator.h"
#include "support/problems_1d.h"
#include "mis/solver.h"

using namespace omis;

namespace {

constexpr double kSigmas = 4.0;

// Moments of T estimates' errors against the exact value.
struct Trials {
    double mean_error = 0, variance = 0, fourth = 0, mean_estimated_variance = 0;
    double sd_estimated_variance = 0, mse = 0;
    int count = 0;
    bool all_finite = true;

    double standard_error() const { return std::sqrt(variance / count); }
    // Standard error of the sample variance, from the sample fourth moment:
    // Var(s²) ≈ (μ₄ − σ⁴)/T.
    double variance_standard_error() const {
        return std::sqrt(std::max(0.0, fourth - variance * variance) / count);
    }
};

Trials run_trials(const Problem1D& p, Strategy s, int rounds, int trials, uint64_t seed,
                  double exact) {
    std::mt19937_64 rng(seed);
    std::vector<double> errors, estimated;
    for (int t = 0; t < trials; ++t) {
        const MisResult r = estimate_problem(p, s, rounds, rng);
        errors.push_back(r.estimate[0] - exact);
        estimated.push_back(r.variance[0]);
    }
    Trials out;
    out.count = trials;
    for (int t = 0; t < trials; ++t) {
        out.all_finite = out.all_finite && std::isfinite(errors[t]) && std::isfinite(estimated[t]);
        out.mean_error += errors[t] / trials;
        out.mean_estimated_variance += estimated[t] / trials;
        out.mse += errors[t] * errors[t] / trials;
    }
    for (int t = 0; t < trials; ++t) {
        const double d = errors[t] - out.mean_error;
        out.variance += d * d / (trials - 1);
        out.fourth += d * d * d * d / trials;
        const double e = estimated[t] - out.mean_estimated_variance;
        out.sd_estimated_variance += e * e / (trials - 1);
    }
    out.sd_estimated_variance = std::sqrt(out.sd_estimated_variance);
    return out;
}

const Strategy kUnbiased[] = {Strategy::Balance, Strategy::Power, Strategy::Maximum,
                              Strategy::Cutoff, Strategy::OptimalProgressive};
const Strategy kHeuristics[] = {Strategy::Balance, Strategy::Power, Strategy::Maximum,
                                Strategy::Cutoff};

}  // namespace

TEST_CASE("unbiased strategies: mean within 4 standard errors of the exact integral",
          "[mis]") {
    for (const Problem1D& p : builtin_problems_1d()) {
        const double F = exact_moments(p).F;
        for (Strategy s : kUnbiased) {
            INFO(p.name << " " << strategy_name(s));
            const Trials t = run_trials(p, s, 8, 4000, 11, F);
            CHECK(t.all_finite);
            CHECK(std::abs(t.mean_error) <= kSigmas * t.standard_error() + 1e-12 * F);
        }
    }
}

TEST_CASE("heuristics: measured variance and the estimator's own variance match the "
          "exact variance", "[mis]") {
    const int R = 8, T = 4000;
    for (const Problem1D& p : builtin_problems_1d()) {
        const double F = exact_moments(p).F;
        for (Strategy s : kHeuristics) {
            INFO(p.name << " " << strategy_name(s));
            const double exact = exact_heuristic_variance(p, s) / R;
            const Trials t = run_trials(p, s, R, T, 23, F);
            CHECK(std::abs(t.variance - exact) <= kSigmas * t.variance_standard_error());
            // The per-technique sample variance is unbiased for the exact one.
            CHECK(std::abs(t.mean_estimated_variance - exact) <=
                  kSigmas * t.sd_estimated_variance / std::sqrt(T));
        }
    }
}

TEST_CASE("optimal-direct is consistent and reaches V_opt ≤ V_bal", "[mis]") {
    for (const Problem1D& p : builtin_problems_1d()) {
        INFO(p.name);
        const ExactMoments exact = exact_moments(p);
        CHECK(exact.v_optimal <= exact.v_balance * (1 + 1e-9));

        const Trials few = run_trials(p, Strategy::OptimalDirect, 4, 2000, 5, exact.F);
        const Trials many = run_trials(p, Strategy::OptimalDirect, 256, 2000, 5, exact.F);
        CHECK(few.all_finite);
        CHECK(many.all_finite);
        // Consistency: the bias at R = 256 is within noise of zero, and the
        // error shrinks with R at least as fast as 1/R up to noise.
        CHECK(std::abs(many.mean_error) <= kSigmas * many.standard_error() + 1e-12 * exact.F);
        CHECK(many.mse <= few.mse * 4.0 / 256.0 * 1.5 + 1e-28);
        // The variance tends to V_opt/R; estimating α inflates it by at most
        // (S−2)/(S−k−2) (solver.h), which at S = 256·Σn is below 2 %.
        const double v_opt = exact.v_optimal / 256;
        const double se = many.variance_standard_error();
        CHECK(many.variance >= v_opt - kSigmas * se);
        CHECK(many.variance <= v_opt * 1.02 + kSigmas * se + 1e-28);
        // Never worse than balance at this sample count, beyond noise.
        const Trials balance = run_trials(p, Strategy::Balance, 256, 2000, 5, exact.F);
        CHECK(many.variance <= balance.variance + kSigmas * balance.variance_standard_error());
    }
}

TEST_CASE("optimal-direct reports its own variance", "[mis]") {
    for (const Problem1D& p : builtin_problems_1d()) {
        INFO(p.name);
        const ExactMoments exact = exact_moments(p);
        const Trials t = run_trials(p, Strategy::OptimalDirect, 64, 2000, 9, exact.F);
        // The mean reported variance is an estimate of the true one: within
        // 4σ of the measured variance (both sides' noise counted), plus the
        // O(k/S) in-sample optimism the solver corrects only to first order.
        const double noise = kSigmas * (t.variance_standard_error() +
                                        t.sd_estimated_variance / std::sqrt(t.count));
        INFO("reported " << t.mean_estimated_variance << " measured " << t.variance);
        CHECK(std::abs(t.mean_estimated_variance - t.variance) <=
              noise + 0.05 * t.variance +
                  1e-15 * exact.F * exact.F);  // + rounding of the expanded moments
    }
}

TEST_CASE("f in the span of the pdfs: optimal has (near) zero error", "[mis]") {
    const Problem1D p = builtin_problems_1d()[2];
    REQUIRE(p.name == "in-span");
    const double F = exact_moments(p).F;
    for (Strategy s : {Strategy::OptimalDirect}) {
        std::mt19937_64 rng(3);
        for (int trial = 0; trial < 50; ++trial) {
            const MisResult r = estimate_problem(p, s, 16, rng);
            CHECK(std::abs(r.estimate[0] - F) <= 1e-12 * F);
            CHECK(r.variance[0] <= 1e-20 * F * F + 1e-12 * F * F / 16);  // rounding of the moments
        }
    }
    // Progressive (cross-fit over epochs): every epoch's α comes from the
    // other ≥ 32 rounds, beyond the 8-samples-per-coefficient minimum, so
    // every round is exact and the variance is rounding only; 1/16 of
    // balance's is a loose bound that any uncorrected round would break.
    const Trials t = run_trials(p, Strategy::OptimalProgressive, 64, 500, 3, F);
    const Trials b = run_trials(p, Strategy::Balance, 64, 500, 3, F);
    CHECK(t.variance < b.variance / 16);
}

TEST_CASE("α ∝ n reproduces the balance estimate bit for bit", "[mis]") {
    const std::vector<int> counts = {1, 3, 2};
    MisEstimator optimal(Strategy::OptimalDirect, 3, 2, counts);
    MisEstimator balance(Strategy::Balance, 3, 2, counts);
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> u(0.01, 3.0);
    for (int r = 0; r < 20; ++r)
        for (int t = 0; t < 3; ++t)
            for (int j = 0; j < counts[t]; ++j) {
                const double pdfs[3] = {u(rng), u(rng), u(rng)}, f[2] = {u(rng), -u(rng)};
                optimal.add_sample(t, pdfs, f);
                balance.add_sample(t, pdfs, f);
            }
    const std::vector<double> reference = balance.result().estimate;
    for (double scale : {0.0, 1.0, 0.37, -5.25, 1e6, 3e-9}) {
        std::vector<double> alpha(6);
        for (int k = 0; k < 3; ++k) alpha[k * 2] = alpha[k * 2 + 1] = scale * counts[k];
        const std::vector<double> e = optimal.control_variate_estimate(alpha);
        CHECK(e[0] == reference[0]);
        CHECK(e[1] == reference[1]);
    }
}

namespace {

// Problems where the system is singular or ill-conditioned.
std::vector<Problem1D> degenerate_problems() {
    auto f = [](double x) { return x * x + 0.1; };
    std::vector<Problem1D> out;
    out.push_back({"identical", f, {linear_up_density(), linear_up_density()}, {1, 1}, {}});
    // A third technique that is never sampled and has zero density on (0,1).
    Density1D absent{"absent", [](double) { return 0.0; }, [](double) { return 0.5; }};
    out.push_back({"zero-density", f, {linear_up_density(), uniform_density(), absent},
                   {1, 1, 0}, {}});
    // Two techniques that differ by 1e-7 relative.
    const double eps = 1e-7;
    Density1D tilted{"tilted", [eps](double x) { return 1 + eps * (2 * x - 1); },
                     [eps](double u) {  // root of x + ε(x² − x) = u
                         return 2 * u / ((1 - eps) + std::sqrt((1 - eps) * (1 - eps) +
                                                               4 * eps * u));
                     }};
    out.push_back({"nearly-coincident", f, {uniform_density(), tilted, linear_up_density()},
                   {1, 1, 1}, {}});
    out.push_back({"all-zero-f", [](double) { return 0.0; },
                   {linear_up_density(), uniform_density()}, {1, 1}, {}});
    return out;
}

}  // namespace

TEST_CASE("singular and ill-conditioned systems stay finite and no worse than balance",
          "[mis]") {
    for (const Problem1D& p : degenerate_problems()) {
        const double F = integrate_1d(p, p.f);
        for (int R : {1, 2, 8, 64}) {
            for (Strategy s : {Strategy::OptimalDirect, Strategy::OptimalProgressive}) {
                INFO(p.name << " R=" << R << " " << strategy_name(s));
                // Same seed: the same samples feed both strategies (paired).
                const Trials opt = run_trials(p, s, R, 1000, 41, F);
                const Trials bal = run_trials(p, Strategy::Balance, R, 1000, 41, F);
                CHECK(opt.all_finite);
                // Within 5 % of balance's mean squared error, beyond noise.
                const double noise = kSigmas * std::sqrt(bal.fourth / bal.count);
                CHECK(opt.mse <= 1.05 * bal.mse + noise + 1e-30);
                if (p.name == "all-zero-f") CHECK(opt.mse == 0.0);
            }
        }
    }
}

TEST_CASE("one single sample gives the balance estimate", "[mis]") {
    for (Strategy s : {Strategy::OptimalDirect, Strategy::OptimalProgressive}) {
        MisEstimator e(s, 2, 1, {1, 0});
        const double pdfs[2] = {0.5, 2.0}, f = 3.0;
        e.add_sample(0, pdfs, &f);
        const MisResult r = e.result();
        CHECK(r.estimate[0] == 3.0 / 0.5);
        CHECK(std::isfinite(r.variance[0]));
    }
}

TEST_CASE("progressive with one round is the balance heuristic", "[mis]") {
    const Problem1D p = builtin_problems_1d()[0];
    std::mt19937_64 a(8), b(8);
    const MisResult prog = estimate_problem(p, Strategy::OptimalProgressive, 1, a);
    const MisResult bal = estimate_problem(p, Strategy::Balance, 1, b);
    CHECK(prog.estimate[0] == Approx(bal.estimate[0]).epsilon(1e-14));
}

TEST_CASE("bad input is refused with a message naming it", "[mis]") {
    using Catch::Matchers::Contains;
    CHECK_THROWS_WITH(MisEstimator(Strategy::Balance, 2, 1, {1}), Contains("counts"));
    CHECK_THROWS_WITH(MisEstimator(Strategy::Balance, 2, 1, {0, 0}), Contains("counts"));
    CHECK_THROWS_WITH(MisEstimator(Strategy::Balance, 2, 5, {1, 1}), Contains("channels"));
    CHECK_THROWS_WITH(MisEstimator(Strategy::Balance, 40, 1, std::vector<int>(40, 1)),
                      Contains("techniques"));
    MisEstimator e(Strategy::OptimalDirect, 2, 1, {1, 1});
    const double f = 1.0, good[2] = {1.0, 1.0}, own_zero[2] = {0.0, 1.0},
                 negative[2] = {1.0, -1.0}, nan_pdf[2] = {1.0, NAN};
    CHECK_THROWS_WITH(e.add_sample(0, own_zero, &f), Contains("own technique"));
    CHECK_THROWS_WITH(e.add_sample(0, negative, &f), Contains("pdfs"));
    CHECK_THROWS_WITH(e.add_sample(0, nan_pdf, &f), Contains("pdfs"));
    CHECK_THROWS_WITH(e.add_sample(2, good, &f), Contains("out of range"));
    const double inf = INFINITY;
    CHECK_THROWS_WITH(e.add_sample(0, good, &inf), Contains("f"));
    CHECK_THROWS_AS(e.result(), std::logic_error);  // no round yet
    e.add_sample(0, good, &f);
    CHECK_THROWS_WITH(e.add_sample(0, good, &f), Contains("round by round"));
    CHECK_THROWS_WITH(e.result(), Contains("incomplete"));
    e.add_sample(1, good, &f);
    CHECK_NOTHROW(e.result());
}

TEST_CASE("solver: coincident techniques are detected as rank deficient", "[mis]") {
    // A for two identical techniques is rank one.
    const double a[4] = {0.25, 0.25, 0.25, 0.25}, b[2] = {0.3, 0.3}, m[1] = {1.0};
    const int counts[2] = {1, 1};
    const SolveResult r = solve_optimal_alpha(2, 1, a, b, m, counts, 1000);
    CHECK(r.rank == 1);
    for (int k = 0; k < 2; ++k) CHECK(std::isfinite(r.alpha[k]));
}

TEST_CASE("solver: rule 4 scales α by λ ∈ [0, 1], toward 1 as samples grow", "[mis]") {
    // Exact moments as if from S samples: the James–Stein factor is
    // λ = 1 − k·P_fit/((S − k − 1)·(P_bal − P_fit)), so it must approach 1 as
    // S grows and the returned α must be λ times the unshrunk solution
    // (taken from a solve with S = 1e15, where λ = 1 to rounding).
    for (const Problem1D& p : builtin_problems_1d()) {
        const ExactMoments ex = exact_moments(p);
        const int N = int(p.techniques.size());
        const double m[1] = {ex.m};
        const SolveResult full =
            solve_optimal_alpha(N, 1, ex.a.data(), ex.b.data(), m, p.counts.data(), 1e15);
        double previous = 0;
        for (double S : {20.0, 200.0, 2000.0, 2e5}) {
            const SolveResult r =
                solve_optimal_alpha(N, 1, ex.a.data(), ex.b.data(), m, p.counts.data(), S);
            INFO(p.name << ", S = " << S << ": λ = " << r.shrink[0]);
            CHECK(r.shrink[0] >= 0);
            CHECK(r.shrink[0] <= 1);
            CHECK(r.shrink[0] >= previous);  // more samples, less shrinkage
            previous = r.shrink[0];
            for (int k = 0; k < N; ++k)
                CHECK(std::abs(r.alpha[k] - r.shrink[0] * full.alpha[k]) <=
                      1e-9 * (std::abs(full.alpha[k]) + 1e-300));
        }
        // With a real gain (V_opt < V_bal), 2e5 samples leave λ close to 1.
        if (ex.v_optimal < 0.9 * ex.v_balance) CHECK(previous > 0.99);
    }
}

TEST_CASE("optimal estimates are never negative when f is not", "[mis]") {
    // The per-estimate guard: with f ≥ 0 everywhere (every built-in problem),
    // no optimal-direct or optimal-progressive estimate may be negative, at
    // the few-sample counts where unguarded solves produced negative values.
    for (const Problem1D& p : builtin_problems_1d())
        for (Strategy s : {Strategy::OptimalDirect, Strategy::OptimalProgressive})
            for (int rounds : {1, 2, 3, 4, 8}) {
                std::mt19937_64 rng(31);
                int negative = 0;
                for (int t = 0; t < 2000; ++t)
                    negative += estimate_problem(p, s, rounds, rng).estimate[0] < 0;
                INFO(p.name << ", " << strategy_name(s) << ", " << rounds << " rounds");
                CHECK(negative == 0);
            }
}
