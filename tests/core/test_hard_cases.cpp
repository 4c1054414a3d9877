// Issue 10's guarantee on the hard-case suite (tests/hard_cases): at 1, 2, 4,
// 8, 16, 64 and 256 samples per technique (one scrambled sequence a point),
// and at 8 and 16 rounds of 8 samples per technique, optimal-direct's and
// optimal-progressive's MSE are at most 1.05 × the balance heuristic's, and
// no estimate is negative (every emitter of the suite emits non-negative
// radiance). Both keep only the part of their correction that the
// sequence's own halves support (the level test, mis/estimator.cpp).
//
// The MSEs come from kCopies independent estimates of each of 8 points per
// case (fixed seeds), so they are themselves noisy. The test compares them
// paired, texel by texel: d = e²_opt − 1.05·e²_bal has mean ≤ 0 under the
// guarantee, and the assertion is mean(d) ≤ 3·SE(d), SE measured from the d
// themselves. A strategy that truly meets the guarantee fails one check with
// probability ≤ 0.13 % (normal approximation of the mean); a real loss of a
// few percent at these counts is larger than 3 SE and fails.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "support/hard_cases.h"

using namespace omis;
using namespace omis::hard_cases;

namespace {

constexpr int kCopies = 32;
constexpr double kAllowed = 1.05;
constexpr double kSigmas = 3.0;

struct PairedExcess {
    double mean = 0, standard_error = 0;
};

PairedExcess paired_excess(const Errors& optimal, const Errors& balance) {
    const std::size_t n = optimal.squared.size();
    std::vector<double> d(n);
    PairedExcess out;
    for (std::size_t i = 0; i < n; ++i) {
        d[i] = optimal.squared[i] - kAllowed * balance.squared[i];
        out.mean += d[i] / n;
    }
    double var = 0;
    for (double x : d) var += (x - out.mean) * (x - out.mean) / (n - 1);
    out.standard_error = std::sqrt(var / n);
    return out;
}

}  // namespace

TEST_CASE("hard cases: optimal MIS never loses to balance and is never negative",
          "[mis][hard]") {
    for (const HardCase& hc : suite()) {
        Scene scene;
        hc.build(scene);
        scene.commit();
        const int points = int(hc.points.size());
        // Reference: 8 copies × 2048 rounds of balance, 64× the largest run
        // below, so its error adds ≤ 1/64 of balance's variance to both MSEs.
        const auto ref = reference(scene, hc, 2048, 8, 777);
        // The suite's counts and 2 and 8 between them (2 spp: the fewest
        // rounds with a level to judge α by; issue 10 measured a 1.23× loss there).
        // Then 8 samples per technique a round at 8 and 16 rounds (8 rounds:
        // the fewest at which optimal-progressive applies its level test; there
        // it lost 1.10 ± 0.03× before, tiny bright case).
        struct Run {
            int per_round, rounds;
        };
        for (Run r : {Run{1, 1}, Run{1, 2}, Run{1, 4}, Run{1, 8}, Run{1, 16}, Run{1, 64},
                      Run{1, 256}, Run{8, 8}, Run{8, 16}}) {
            const std::vector<int> counts(hc.techniques.size(), r.per_round);
            auto errors_of = [&](Strategy s) {
                return errors(run_counts(scene, hc, s, counts, r.rounds, kCopies, 5), ref,
                              points, kCopies);
            };
            const Errors balance = errors_of(Strategy::Balance);
            for (Strategy s : {Strategy::OptimalDirect, Strategy::OptimalProgressive}) {
                const Errors optimal = errors_of(s);
                const PairedExcess excess = paired_excess(optimal, balance);
                INFO(hc.name << ", " << r.rounds << " rounds of " << r.per_round << ", "
                             << strategy_name(s) << ": MSE ratio "
                             << optimal.mse / balance.mse << ", paired excess " << excess.mean
                             << " ± " << excess.standard_error);
                CHECK(excess.mean <= kSigmas * excess.standard_error);
                CHECK(optimal.negative == 0);
            }
        }
    }
}

TEST_CASE("hard cases: sample allocation's choice never loses more than 3× at equal samples",
          "[mis][hard]") {
    // Allocation (issue 10, item 2) against the same two calls keeping one
    // sample per technique a round (run_allocated, choose = false): the same
    // pilot, the same samples, only the split of the later ones differs.
    // The bound is loose on purpose: it catches a broken allocation (reused or
    // skipped sequence points, a technique starved below its floor), not a
    // poor choice. The allocation minimises the variance of independent
    // draws, while each technique draws a scrambled Sobol' sequence whose
    // error falls faster at power-of-two counts — which the equal split
    // reaches here and a chosen split does not. Measured (bench_hard_cases
    // --allocation-gain 32, seed 42): at most 1.9 ± 0.4× with 4 streams a
    // point, 2.5 ± 0.4× with one (the dim corner at 64 spp), and gains to
    // 0.5× elsewhere. Paired test as above: mean of e²_alloc − 3·e²_kept ≤ 3 SE
    // (fixed seeds).
    constexpr double kAllocationBound = 3.0;
    for (const HardCase& hc : suite()) {
        Scene scene;
        hc.build(scene);
        scene.commit();
        const int points = int(hc.points.size());
        const auto ref = reference(scene, hc, 2048, 8, 777);
        for (int spp : {16, 64}) {
            const Errors kept = errors(run_allocated(scene, hc, Strategy::OptimalDirect, spp,
                                                     spp / 4, kCopies, 5, false).values,
                                       ref, points, kCopies);
            const Errors chosen = errors(run_allocated(scene, hc, Strategy::OptimalDirect, spp,
                                                       spp / 4, kCopies, 5).values,
                                         ref, points, kCopies);
            const std::size_t n = chosen.squared.size();
            double mean = 0, var = 0;
            for (std::size_t i = 0; i < n; ++i)
                mean += (chosen.squared[i] - kAllocationBound * kept.squared[i]) / n;
            for (std::size_t i = 0; i < n; ++i) {
                const double d = chosen.squared[i] - kAllocationBound * kept.squared[i] - mean;
                var += d * d / (n - 1);
            }
            INFO(hc.name << ", " << spp << " spp: MSE ratio " << chosen.mse / kept.mse);
            CHECK(mean <= kSigmas * std::sqrt(var / n));
            CHECK(chosen.negative == 0);
        }
    }
}
