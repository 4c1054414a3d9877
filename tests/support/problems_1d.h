// Analytic 1-D integration problems on (0, 1) with exact moments by quadrature.
// They drive the estimator demo, its tests and its benchmark: every strategy's
// true variance is known, so measured variances can be checked against it.
#pragma once

#include <functional>
#include <random>
#include <string>
#include <vector>

#include "mis/estimator.h"
#include "mis/strategy.h"

namespace omis {

// A sampling technique on (0, 1): density and its inverse-CDF sampler.
struct Density1D {
    std::string name;
    std::function<double(double)> pdf;
    std::function<double(double)> sample;  // u in [0,1) → x distributed by pdf
};

struct Problem1D {
    std::string name;
    std::function<double(double)> f;
    std::vector<Density1D> techniques;
    std::vector<int> counts;       // n_k per round
    std::vector<double> breaks;    // kinks/discontinuities in (0,1) for quadrature
};

// Exact per-round quantities of SPEC §1–§2 (divide a variance by R for an
// estimate over R rounds).
struct ExactMoments {
    double F = 0;
    std::vector<double> a, b;  // A (N×N), b (N)
    double m = 0;              // ∫ f²/q
    std::vector<double> alpha;  // solution of A α = b (unregularised)
    double v_optimal = 0;       // V(α*)
    double v_balance = 0;
};

// ∫_0^1 g, composite Gauss–Legendre split at the problem's breaks.
double integrate_1d(const Problem1D& problem, const std::function<double(double)>& g);

ExactMoments exact_moments(const Problem1D& problem);

// Exact per-round variance of a heuristic strategy:
// Σ_t ∫ w_t² f²/(n_t p_t) − Σ_t (∫ w_t f)²/n_t.
double exact_heuristic_variance(const Problem1D& problem, Strategy strategy,
                                const StrategyOptions& options = {});

// One estimate of the problem's integral with `rounds` rounds of samples drawn
// from rng, combined with `strategy`.
MisResult estimate_problem(const Problem1D& problem, Strategy strategy, int rounds,
                           std::mt19937_64& rng, const StrategyOptions& options = {});

// The built-in problems of the demo, benchmark and tests.
std::vector<Problem1D> builtin_problems_1d();

// Densities with closed-form inverse CDFs, for writing more problems.
Density1D uniform_density();
Density1D linear_up_density();            // 2x
Density1D linear_down_density();          // 2(1 − x)
Density1D exponential_density(double rate);  // ∝ e^(−rate·x)
Density1D cauchy_density(double centre, double width);  // ∝ 1/(1 + ((x−c)/w)²)
Density1D step_density(double split, double left_mass);  // constant on each side

}  // namespace omis
