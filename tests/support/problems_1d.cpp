#include "support/problems_1d.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "mis/solver.h"

namespace omis {
namespace {

// 8-point Gauss–Legendre nodes and weights on (−1, 1).
constexpr std::array<double, 4> kNodes = {0.1834346424956498, 0.5255324099163290,
                                          0.7966664774136267, 0.9602898564975363};
constexpr std::array<double, 4> kWeights = {0.3626837833783620, 0.3137066458778873,
                                            0.2223810344533745, 0.1012285362903763};
constexpr int kPanelsPerSegment = 4000;

// Reference solve of the exact system (dense Gaussian elimination
// with partial pivoting; the built-in problems are well conditioned).
std::vector<double> dense_solve(std::vector<double> a, std::vector<double> b) {
    const int n = int(b.size());
    for (int k = 0; k < n; ++k) {
        int p = k;
        for (int i = k + 1; i < n; ++i)
            if (std::abs(a[i * n + k]) > std::abs(a[p * n + k])) p = i;
        for (int j = 0; j < n; ++j) std::swap(a[k * n + j], a[p * n + j]);
        std::swap(b[k], b[p]);
        for (int i = k + 1; i < n; ++i) {
            const double l = a[i * n + k] / a[k * n + k];
            for (int j = k; j < n; ++j) a[i * n + j] -= l * a[k * n + j];
            b[i] -= l * b[k];
        }
    }
    for (int k = n - 1; k >= 0; --k) {
        for (int j = k + 1; j < n; ++j) b[k] -= a[k * n + j] * b[j];
        b[k] /= a[k * n + k];
    }
    return b;
}

double mixture(const Problem1D& p, double x, std::vector<double>& pdfs) {
    double q = 0;
    for (size_t k = 0; k < p.techniques.size(); ++k) {
        pdfs[k] = p.techniques[k].pdf(x);
        q += p.counts[k] * pdfs[k];
    }
    return q;
}

}  // namespace

double integrate_1d(const Problem1D& problem, const std::function<double(double)>& g) {
    std::vector<double> cuts = {0.0};
    for (double b : problem.breaks)
        if (b > 0 && b < 1) cuts.push_back(b);
    cuts.push_back(1.0);
    std::sort(cuts.begin(), cuts.end());
    double total = 0;
    for (size_t s = 0; s + 1 < cuts.size(); ++s) {
        const double h = (cuts[s + 1] - cuts[s]) / kPanelsPerSegment;
        for (int panel = 0; panel < kPanelsPerSegment; ++panel) {
            const double mid = cuts[s] + (panel + 0.5) * h, half = 0.5 * h;
            double sum = 0;
            for (size_t i = 0; i < kNodes.size(); ++i)
                sum += kWeights[i] * (g(mid - half * kNodes[i]) + g(mid + half * kNodes[i]));
            total += sum * half;
        }
    }
    return total;
}

ExactMoments exact_moments(const Problem1D& problem) {
    const int N = int(problem.techniques.size());
    ExactMoments out;
    out.a.assign(N * N, 0.0);
    out.b.assign(N, 0.0);
    std::vector<double> pdfs(N);
    out.F = integrate_1d(problem, problem.f);
    out.m = integrate_1d(problem, [&](double x) {
        const double q = mixture(problem, x, pdfs);
        const double f = problem.f(x);
        return q > 0 ? f * f / q : 0.0;
    });
    for (int i = 0; i < N; ++i) {
        out.b[i] = integrate_1d(problem, [&](double x) {
            const double q = mixture(problem, x, pdfs);
            return q > 0 ? pdfs[i] * problem.f(x) / q : 0.0;
        });
        for (int j = i; j < N; ++j)
            out.a[i * N + j] = out.a[j * N + i] = integrate_1d(problem, [&](double x) {
                const double q = mixture(problem, x, pdfs);
                return q > 0 ? pdfs[i] * pdfs[j] / q : 0.0;
            });
    }
    out.alpha = dense_solve(out.a, out.b);
    const std::vector<double> zero(N, 0.0);
    out.v_optimal = round_variance(N, 1, 0, out.a.data(), out.b.data(), &out.m,
                                   problem.counts.data(), out.alpha.data());
    out.v_balance = round_variance(N, 1, 0, out.a.data(), out.b.data(), &out.m,
                                   problem.counts.data(), zero.data());
    return out;
}

double exact_heuristic_variance(const Problem1D& problem, Strategy strategy,
                                const StrategyOptions& options) {
    const int N = int(problem.techniques.size());
    std::vector<double> pdfs(N);
    double v = 0;
    for (int t = 0; t < N; ++t) {
        const double n_t = problem.counts[t];
        if (n_t == 0) continue;
        auto weighted = [&](double x, bool squared) {
            mixture(problem, x, pdfs);
            if (!(pdfs[t] > 0)) return 0.0;
            const double w = heuristic_weight(strategy, options, N, problem.counts.data(),
                                              pdfs.data(), t);
            const double f = problem.f(x);
            return squared ? w * w * f * f / (n_t * pdfs[t]) : w * f;
        };
        const double second = integrate_1d(problem, [&](double x) { return weighted(x, true); });
        const double first = integrate_1d(problem, [&](double x) { return weighted(x, false); });
        v += second - first * first / n_t;
    }
    return v;
}

MisResult estimate_problem(const Problem1D& problem, Strategy strategy, int rounds,
                           std::mt19937_64& rng, const StrategyOptions& options) {
    const int N = int(problem.techniques.size());
    MisEstimator estimator(strategy, N, 1, problem.counts, options);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::vector<double> pdfs(N);
    for (int r = 0; r < rounds; ++r)
        for (int t = 0; t < N; ++t)
            for (int j = 0; j < problem.counts[t]; ++j) {
                const double x = problem.techniques[t].sample(uniform(rng));
                for (int k = 0; k < N; ++k) pdfs[k] = problem.techniques[k].pdf(x);
                const double f = problem.f(x);
                estimator.add_sample(t, pdfs.data(), &f);
            }
    return estimator.result();
}

Density1D uniform_density() {
    return {"uniform", [](double) { return 1.0; }, [](double u) { return u; }};
}

Density1D linear_up_density() {
    return {"2x", [](double x) { return 2 * x; },
            [](double u) { return std::sqrt(u); }};
}

Density1D linear_down_density() {
    return {"2(1-x)", [](double x) { return 2 * (1 - x); },
            [](double u) { return 1 - std::sqrt(1 - u); }};
}

Density1D exponential_density(double rate) {
    const double norm = -std::expm1(-rate);  // 1 − e^(−rate)
    return {"exp(" + std::to_string(rate) + ")",
            [=](double x) { return rate * std::exp(-rate * x) / norm; },
            [=](double u) { return -std::log1p(-u * norm) / rate; }};
}

Density1D cauchy_density(double centre, double width) {
    const double lo = std::atan((0 - centre) / width), hi = std::atan((1 - centre) / width);
    const double norm = width * (hi - lo);
    return {"cauchy",
            [=](double x) {
                const double t = (x - centre) / width;
                return 1.0 / (norm * (1 + t * t));
            },
            [=](double u) { return centre + width * std::tan(lo + u * (hi - lo)); }};
}

Density1D step_density(double split, double left_mass) {
    const double left = left_mass / split, right = (1 - left_mass) / (1 - split);
    return {"step",
            [=](double x) { return x < split ? left : right; },
            [=](double u) {
                return u < left_mass ? u / left : split + (u - left_mass) / right;
            }};
}

std::vector<Problem1D> builtin_problems_1d() {
    std::vector<Problem1D> problems;
    // A sharp peak (a glossy lobe) on a broad ramp (a diffuse term): neither
    // technique fits alone; the paper's motivating situation.
    problems.push_back({"peak-on-ramp",
                        [](double x) {
                            const double t = (x - 0.3) / 0.05;
                            return 1 / (1 + t * t) + 0.5 * x;
                        },
                        {uniform_density(), cauchy_density(0.3, 0.05)},
                        {1, 1},
                        {}});
    // Three techniques, f outside their span.
    problems.push_back({"three-ramps",
                        [](double x) { return x * x + 0.2; },
                        {linear_up_density(), linear_down_density(), uniform_density()},
                        {1, 1, 1},
                        {}});
    // f inside the span of the pdfs: the optimal combination has zero variance.
    problems.push_back({"in-span",
                        [](double x) { return 3 * (2 * x) + 1 * (2 * (1 - x)); },
                        {linear_up_density(), linear_down_density()},
                        {1, 1},
                        {}});
    // A discontinuous integrand and a step density, unequal counts.
    problems.push_back({"window",
                        [](double x) { return (x > 0.5 && x < 0.7) ? 1.0 : 0.0; },
                        {uniform_density(), step_density(0.5, 0.1)},
                        {2, 1},
                        {0.5, 0.7}});
    // An exponential falloff with a ripple, sampled by a matching exponential.
    problems.push_back({"ripple-falloff",
                        [](double x) { return std::exp(-5 * x) * (1 + 0.5 * std::sin(12 * x)); },
                        {exponential_density(5.0), uniform_density()},
                        {1, 1},
                        {}});
    return problems;
}

}  // namespace omis
