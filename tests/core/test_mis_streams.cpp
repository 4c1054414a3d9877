// The estimator's pieces for per-stream shading (issue 10, overhead): a whole
// made up of its streams (add_rounds) equals the whole accumulated sample by
// sample, and a stream's estimate with the whole's α (corrected_estimates)
// equals the control-variate estimate for that α. These are identities of
// sums, so they are checked to rounding (relative 1e-12), not statistically.
#include <catch2/catch.hpp>

#include <random>
#include <stdexcept>
#include <vector>

#include "mis/estimator.h"

using namespace omis;

namespace {

// Two techniques on [0,1): uniform (p = 1) and linear (p = 2x); f = x² + 0.1,
// three channels scaled 1, 2, 3. Adds `rounds` rounds of counts {2, 1} to
// every estimator in `into`.
void add_rounds_to(std::vector<MisEstimator*> into, int rounds, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int counts[2] = {2, 1};
    for (int r = 0; r < rounds; ++r)
        for (int t = 0; t < 2; ++t)
            for (int j = 0; j < counts[t]; ++j) {
                const double x = t == 0 ? u(rng) : std::sqrt(u(rng));
                const double pdfs[2] = {1.0, 2 * x};
                const double v = x * x + 0.1, f[3] = {v, 2 * v, 3 * v};
                for (MisEstimator* e : into) e->add_sample(t, pdfs, f);
            }
}

}  // namespace

TEST_CASE("mis streams: the sum of streams is the whole", "[mis]") {
    for (Strategy s : {Strategy::Balance, Strategy::Power, Strategy::OptimalDirect}) {
        MisEstimator whole(s, 2, 3, {2, 1}), summed(s, 2, 3, {2, 1});
        std::vector<MisEstimator> streams(4, MisEstimator(s, 2, 3, {2, 1}));
        std::mt19937_64 rng(7);
        for (int k = 0; k < 4; ++k) add_rounds_to({&whole, &streams[k]}, 3 + k, rng);
        for (const MisEstimator& e : streams) summed.add_rounds(e);
        const MisResult a = whole.result(), b = summed.result();
        INFO(strategy_name(s));
        CHECK(a.rounds == b.rounds);
        for (int c = 0; c < 3; ++c) {
            CHECK(b.estimate[c] == Approx(a.estimate[c]).epsilon(1e-12));
            CHECK(b.variance[c] == Approx(a.variance[c]).epsilon(1e-12));
        }
    }
}

TEST_CASE("mis streams: a stream with the whole's alpha is the control variate", "[mis]") {
    MisEstimator whole(Strategy::OptimalDirect, 2, 3, {2, 1});
    MisEstimator stream(Strategy::OptimalDirect, 2, 3, {2, 1});
    std::mt19937_64 rng(11);
    add_rounds_to({&whole}, 40, rng);
    add_rounds_to({&whole, &stream}, 10, rng);
    const MisResult r = whole.result();
    REQUIRE(r.alpha.size() == 6);
    double corrected[3], balance[3];
    stream.corrected_estimates(r.alpha.data(), corrected);
    stream.balance_estimates(balance);
    const std::vector<double> reference = stream.control_variate_estimate(r.alpha);
    for (int c = 0; c < 3; ++c) {
        CHECK(corrected[c] == Approx(reference[c]).epsilon(1e-12));
        CHECK(balance[c] == Approx(stream.balance_estimate(c)).epsilon(1e-12));
    }
    // The whole's own estimate with its α (no fallback here: f is smooth).
    double own[3];
    whole.corrected_estimates(r.alpha.data(), own);
    for (int c = 0; c < 3; ++c) CHECK(own[c] == Approx(r.estimate[c]).epsilon(1e-12));
}

TEST_CASE("mis streams: add_rounds refuses mismatched or progressive estimators", "[mis]") {
    MisEstimator a(Strategy::OptimalDirect, 2, 3, {2, 1});
    const MisEstimator other_counts(Strategy::OptimalDirect, 2, 3, {1, 1});
    const MisEstimator other_strategy(Strategy::Balance, 2, 3, {2, 1});
    CHECK_THROWS_AS(a.add_rounds(other_counts), std::logic_error);
    CHECK_THROWS_AS(a.add_rounds(other_strategy), std::logic_error);
    MisEstimator p(Strategy::OptimalProgressive, 2, 3, {2, 1});
    CHECK_THROWS_AS(p.add_rounds(p), std::logic_error);
    const double pdfs[2] = {1.0, 1.0}, f[3] = {1, 1, 1};
    MisEstimator open(Strategy::OptimalDirect, 2, 3, {2, 1});
    open.add_sample(0, pdfs, f);  // a round left open
    CHECK_THROWS_AS(a.add_rounds(open), std::logic_error);
}
