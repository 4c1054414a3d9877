// Issue 2's note, issue 10's guarantee on the 1-D problems: with 4 to 9
// samples per solve, optimal-direct and optimal-progressive lose nothing
// against the balance heuristic (MSE ≤ 1.05 × balance's).
//
// Both strategies see the same samples (the same seed drives the same draws),
// so the comparison is paired: d = e²_opt − 1.05·e²_bal per trial, and the
// check is mean(d) ≤ 3·SE(d) with SE measured from the d. A strategy that
// meets the guarantee fails a check with probability ≤ 0.13 %; the ~20 %
// loss issue 2 measured is many SE above the bound at 4000 trials.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "support/problems_1d.h"

using namespace omis;

TEST_CASE("4–9 samples per solve: optimal MIS is no worse than balance", "[mis]") {
    constexpr int kTrials = 4000;
    for (const Problem1D& p : builtin_problems_1d()) {
        const double F = exact_moments(p).F;
        int per_round = 0;
        for (int n : p.counts) per_round += n;
        for (int rounds = 1; rounds * per_round <= 9; ++rounds) {
            if (rounds * per_round < 4) continue;
            for (Strategy s : {Strategy::OptimalDirect, Strategy::OptimalProgressive}) {
                std::mt19937_64 rng_opt(11), rng_bal(11);
                std::vector<double> d(kTrials);
                double mean = 0, mse_opt = 0, mse_bal = 0;
                for (int t = 0; t < kTrials; ++t) {
                    const double e_opt = estimate_problem(p, s, rounds, rng_opt).estimate[0] - F;
                    const double e_bal =
                        estimate_problem(p, Strategy::Balance, rounds, rng_bal).estimate[0] - F;
                    d[t] = e_opt * e_opt - 1.05 * e_bal * e_bal;
                    mean += d[t] / kTrials;
                    mse_opt += e_opt * e_opt / kTrials;
                    mse_bal += e_bal * e_bal / kTrials;
                }
                double var = 0;
                for (double x : d) var += (x - mean) * (x - mean) / (kTrials - 1);
                INFO(p.name << ", " << rounds * per_round << " samples, " << strategy_name(s)
                            << ": MSE ratio " << mse_opt / mse_bal);
                CHECK(mean <= 3 * std::sqrt(var / kTrials) + 1e-30 * F * F);
            }
        }
    }
}
