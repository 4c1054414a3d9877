// The estimator's per-stream sums (issue 10, overhead): a stream's estimate
// from the whole's sums (set_streams, stream_estimates) equals that of an
// estimator fed the stream's samples alone — balance or heuristic estimate,
// and the control variate with a given α — and keeping the sums leaves the
// whole's result unchanged. These are identities of sums, so they are
// checked to rounding (relative 1e-12), not statistically.
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

TEST_CASE("mis streams: a stream's sums give the stream's own estimates", "[mis]") {
    for (Strategy s : {Strategy::Balance, Strategy::Power, Strategy::OptimalDirect}) {
        INFO(strategy_name(s));
        MisEstimator whole(s, 2, 3, {2, 1}), plain(s, 2, 3, {2, 1});
        std::vector<MisEstimator> alone(3, MisEstimator(s, 2, 3, {2, 1}));
        whole.set_streams(3);
        std::mt19937_64 rng(7);
        // Rounds dealt to streams 0, 1, 2, 0, 1, 2, ... as the renderer does.
        for (int r = 0; r < 12; ++r) {
            whole.set_stream(r % 3);
            add_rounds_to({&whole, &plain, &alone[r % 3]}, 1, rng);
        }
        const MisResult w = whole.result(), p = plain.result();
        for (int c = 0; c < 3; ++c) CHECK(w.estimate[c] == p.estimate[c]);
        const std::vector<double> alpha = {0.3, -0.2, 0.5, 0.1, 0.7, -0.4};
        for (int k = 0; k < 3; ++k) {
            CHECK(whole.stream_rounds(k) == 4);
            double balance[3];
            whole.stream_estimates(k, nullptr, balance);
            for (int c = 0; c < 3; ++c)
                CHECK(balance[c] == Approx(alone[k].balance_estimate(c)).epsilon(1e-12));
            if (s != Strategy::OptimalDirect) continue;
            // β without n-component (n = (2, 1)): β·n = 0 per channel.
            std::vector<double> beta(6);
            for (int c = 0; c < 3; ++c) {
                const double t = (2 * alpha[c] + alpha[3 + c]) / 5;
                beta[c] = alpha[c] - 2 * t;
                beta[3 + c] = alpha[3 + c] - t;
            }
            double again[3], corrected[3];
            whole.stream_estimates(k, beta.data(), again, corrected);
            for (int c = 0; c < 3; ++c) CHECK(again[c] == balance[c]);
            const std::vector<double> reference = alone[k].control_variate_estimate(alpha);
            for (int c = 0; c < 3; ++c)
                CHECK(corrected[c] == Approx(reference[c]).epsilon(1e-12));
        }
    }
}

TEST_CASE("mis streams: bad stream use is refused", "[mis]") {
    MisEstimator p(Strategy::OptimalProgressive, 2, 3, {2, 1});
    CHECK_THROWS_AS(p.set_streams(4), std::logic_error);
    MisEstimator e(Strategy::OptimalDirect, 2, 3, {2, 1});
    CHECK_THROWS_AS(e.set_streams(-1), std::invalid_argument);
    e.set_streams(2);
    CHECK_THROWS_AS(e.set_stream(2), std::invalid_argument);
    const double pdfs[2] = {1.0, 1.0}, f[3] = {1, 1, 1};
    e.add_sample(0, pdfs, f);  // a round left open
    CHECK_THROWS_AS(e.set_stream(1), std::logic_error);
}
