// Estimator benchmark and demo table.
//   --table   the 1-D problems: exact V_bal and V_opt, and the measured variance
//             of every strategy (the README's main job until baking exists)
//   --timing  ns per accumulated sample and µs per solve for N = 2, 3, 4, 8 (RGB)
// Without arguments: both.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "mis/estimator.h"
#include "support/problems_1d.h"
#include "mis/solver.h"

using namespace omis;
using Clock = std::chrono::steady_clock;

namespace {

const Strategy kAll[] = {Strategy::Balance,       Strategy::Power,
                         Strategy::Maximum,       Strategy::Cutoff,
                         Strategy::OptimalDirect, Strategy::OptimalProgressive};

void print_table(int rounds, int trials) {
    std::printf("1-D problems on (0,1): variance of one estimate over R = %d rounds, "
                "measured over %d independent estimates (seeded)\n\n", rounds, trials);
    for (const Problem1D& problem : builtin_problems_1d()) {
        const ExactMoments exact = exact_moments(problem);
        std::printf("%s   F = %.6g   techniques:", problem.name.c_str(), exact.F);
        for (size_t k = 0; k < problem.techniques.size(); ++k)
            std::printf(" %s×%d", problem.techniques[k].name.c_str(), problem.counts[k]);
        std::printf("\n  exact V_bal = %.4e   exact V_opt = %.4e   V_opt/V_bal = %.3f\n",
                    exact.v_balance / rounds, exact.v_optimal / rounds,
                    exact.v_optimal / exact.v_balance);
        std::printf("  %-20s %12s %12s %9s %12s %9s\n", "strategy", "exact Var",
                    "measured Var", "meas/ex", "mean est.Var", "bias/σ");
        for (Strategy s : kAll) {
            std::mt19937_64 rng(1234);
            double sum = 0, sum2 = 0, sum_var = 0;
            for (int t = 0; t < trials; ++t) {
                const MisResult r = estimate_problem(problem, s, rounds, rng);
                const double e = r.estimate[0] - exact.F;
                sum += e;
                sum2 += e * e;
                sum_var += r.variance[0];
            }
            const double mean_err = sum / trials;
            const double var = (sum2 - trials * mean_err * mean_err) / (trials - 1);
            double exact_var = NAN;
            if (!is_optimal(s))
                exact_var = exact_heuristic_variance(problem, s) / rounds;
            else if (s == Strategy::OptimalDirect)
                exact_var = exact.v_optimal / rounds;  // asymptotic
            // Errors at rounding level (f in the span) make bias/σ meaningless.
            const double sigma_mean = std::sqrt(var / trials);
            const bool rounding = var <= 1e-24 * exact.F * exact.F;
            std::printf("  %-20s %12.4e %12.4e %9.3f %12.4e %9s\n", strategy_name(s),
                        exact_var, var, var / exact_var, sum_var / trials,
                        rounding ? "exact"
                                 : std::to_string(std::round(100 * mean_err / sigma_mean) / 100)
                                       .substr(0, 5)
                                       .c_str());
        }
        std::printf("\n");
    }
    std::printf("exact Var of optimal-direct is the asymptotic V_opt/R; progressive has "
                "no closed form (its early rounds use coarse α).\n");
}

// Random samples with N pdfs and RGB f, prepared outside the timed loop.
struct SampleSet {
    int N;
    std::vector<int> technique;
    std::vector<double> pdfs, f;
};

SampleSet make_samples(int N, int rounds) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0.05, 2.0);
    SampleSet set{N, {}, {}, {}};
    for (int r = 0; r < rounds; ++r)
        for (int t = 0; t < N; ++t) {
            set.technique.push_back(t);
            for (int k = 0; k < N; ++k) set.pdfs.push_back(u(rng));
            for (int c = 0; c < 3; ++c) set.f.push_back(u(rng));
        }
    return set;
}

void print_timing() {
    std::printf("Accumulation (ns per sample, RGB, one core) and solve (µs per solve)\n");
    std::printf("  %3s %10s %10s %10s %14s %12s\n", "N", "balance", "power",
                "opt-direct", "opt-progr.", "solve µs");
    for (int N : {2, 3, 4, 8}) {
        const int rounds = 200000 / N;
        const SampleSet set = make_samples(N, rounds);
        const std::vector<int> counts(N, 1);
        std::printf("  %3d", N);
        for (Strategy s : {Strategy::Balance, Strategy::Power, Strategy::OptimalDirect,
                           Strategy::OptimalProgressive}) {
            double best = 1e30;
            for (int rep = 0; rep < 5; ++rep) {
                MisEstimator e(s, N, 3, counts);
                const auto t0 = Clock::now();
                e.add_samples(set.technique.size(), set.technique.data(), sizeof(int),
                              set.pdfs.data(), sizeof(double) * N, set.f.data(),
                              sizeof(double) * 3);
                const double ns =
                    std::chrono::duration<double, std::nano>(Clock::now() - t0).count();
                best = std::min(best, ns / set.technique.size());
            }
            std::printf(s == Strategy::OptimalProgressive ? " %14.1f" : " %10.1f", best);
        }
        // Solve: moments of the sample set, solved repeatedly.
        std::vector<double> a(N * N, 0.0), b(N * 3, 0.0);
        for (size_t s = 0; s < set.technique.size(); ++s) {
            const double* p = &set.pdfs[s * N];
            double q = 0;
            for (int k = 0; k < N; ++k) q += p[k];
            for (int i = 0; i < N; ++i) {
                for (int j = 0; j < N; ++j) a[i * N + j] += p[i] * p[j] / (q * q);
                for (int c = 0; c < 3; ++c) b[i * 3 + c] += p[i] * set.f[s * 3 + c] / (q * q);
            }
        }
        const double m[3] = {10.0, 10.0, 10.0};
        const int solves = 200000;
        double best = 1e30, sink = 0;
        for (int rep = 0; rep < 5; ++rep) {
            const auto t0 = Clock::now();
            for (int i = 0; i < solves; ++i) {
                a[0] += 1e-300;  // defeat hoisting
                sink += solve_optimal_alpha(N, 3, a.data(), b.data(), m, counts.data(), 1e6).alpha[0];
            }
            const double us =
                std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
            best = std::min(best, us / solves);
        }
        std::printf(" %12.3f\n", best + sink * 0);
    }
}

}  // namespace

int main(int argc, char** argv) {
    bool table = argc < 2, timing = argc < 2;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--table")) table = true;
        else if (!std::strcmp(argv[i], "--timing")) timing = true;
        else {
            std::fprintf(stderr, "usage: %s [--table] [--timing]\n", argv[0]);
            return 2;
        }
    }
    if (table) print_table(64, 400);
    if (timing) print_timing();
    return 0;
}
