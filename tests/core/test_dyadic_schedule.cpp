// Time-budget passes end on powers of two (bake/dyadic_schedule.h): the pass
// sizes, the tail's weight, the rate α measured from the running means, and a
// bake under a time budget that keeps its estimate unbiased.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "bake/bake.h"
#include "bake/dyadic_schedule.h"
#include "render/scene.h"
#include "render/techniques.h"
#include "support/floor_lambert.h"

using namespace omis;

TEST_CASE("dyadic passes: to 2N, 4N or 8N, then tails that halve", "[bake][schedule]") {
    const int lots = 1 << 30;
    // From N rounds: 8N wherever 7N fit with the margin, else 4N wherever 3N
    // do (one pass, one fixed part, where 2N then 4N would pay two), else 2N.
    CHECK(next_dyadic_pass(1, 100, 1, lots).rounds == 7);
    CHECK(next_dyadic_pass(1, 7.07 / kGrowthMargin, 1, lots).rounds == 7);
    CHECK(next_dyadic_pass(1, 6.93 / kGrowthMargin, 1, lots).rounds == 3);
    CHECK(next_dyadic_pass(1, 3.03 / kGrowthMargin, 1, lots).rounds == 3);
    CHECK(next_dyadic_pass(1, 2.97 / kGrowthMargin, 1, lots).rounds == 1);
    CHECK(next_dyadic_pass(4, 28.1 / kGrowthMargin, 1, lots).rounds == 28);
    CHECK(next_dyadic_pass(4, 27.9 / kGrowthMargin, 1, lots).rounds == 12);
    CHECK(next_dyadic_pass(4, 12.1 / kGrowthMargin, 1, lots).rounds == 12);
    CHECK(next_dyadic_pass(4, 11.9 / kGrowthMargin, 1, lots).rounds == 4);
    CHECK_FALSE(next_dyadic_pass(4, 11.9 / kGrowthMargin, 1, lots).tail);
    CHECK(next_dyadic_pass(4, 100, 1, 27).rounds == 12);  // 7N beyond the rounds left
    CHECK(next_dyadic_pass(4, 100, 1, 11).rounds == 4);   // 3N too
    // Growth never passes 8N, however much fits.
    CHECK(next_dyadic_pass(2, 1e6, 1, lots).rounds == 14);
    // No overflow near the largest sample budgets.
    CHECK(next_dyadic_pass(1 << 28, 1e12, 1, lots).rounds == 3 << 28);
    // 2N does not fit: a tail, the largest power of two that fits.
    DyadicPass p = next_dyadic_pass(32, 31, 1, lots);
    CHECK(p.rounds == 16);
    CHECK(p.tail);
    CHECK(next_dyadic_pass(32, 9, 1, lots).rounds == 8);
    // After a tail, only smaller tails (32 + 8: at most 4).
    CHECK(next_dyadic_pass(40, 100, 1, lots).rounds == 4);
    CHECK(next_dyadic_pass(40, 100, 1, lots).tail);
    // No tail below N/16, nothing when a round does not fit.
    CHECK(next_dyadic_pass(64, 3.9, 1, lots).rounds == 0);
    CHECK(next_dyadic_pass(64, 4, 1, lots).rounds == 4);
    CHECK(next_dyadic_pass(8, 0.5, 1, lots).rounds == 0);
    // After a dropped probe: the first net of at least min_rounds.
    CHECK(next_dyadic_pass(0, 100, 3, lots).rounds == 4);
    CHECK(next_dyadic_pass(0, 3, 3, lots).rounds == 0);
    // A sample budget's last rounds are taken as asked.
    CHECK(next_dyadic_pass(64, 1000, 1, 40).rounds == 40);
    CHECK_FALSE(next_dyadic_pass(64, 1000, 1, 40).tail);
}

TEST_CASE("after an optimal strategy's probe: a first net from round 0, else the probe stays",
          "[bake][schedule]") {
    const int lots = 1 << 20;
    // The first net of min_rounds fits: it replaces the probe.
    PassAfterProbe after = pass_after_probe(1, 10, 4, lots);
    CHECK_FALSE(after.keep_probe);
    CHECK(after.pass.rounds == 4);
    // It does not: the probe is the first round, the next pass takes it to 2.
    after = pass_after_probe(1, 2.5, 4, lots);
    CHECK(after.keep_probe);
    CHECK(after.pass.rounds == 1);
    CHECK_FALSE(after.pass.tail);
    // ... or to 4 where three rounds fit.
    after = pass_after_probe(1, 3.03 / kGrowthMargin, 8, lots);
    CHECK(after.keep_probe);
    CHECK(after.pass.rounds == 3);
    // Not even a round fits: the bake ends on the probe.
    after = pass_after_probe(1, 0.9, 4, lots);
    CHECK(after.keep_probe);
    CHECK(after.pass.rounds == 0);
}

TEST_CASE("a measured first pass: a net with room to double, the largest net, or all rounds",
          "[bake][schedule]") {
    const int lots = 1 << 20;
    // emissive_mesh's 0.05 s: ~3.2 rounds fit, 2.56 with the margin: a net of
    // 2 in one pass (a second would not fit).
    CHECK(measured_first_pass(3.2, lots) == 2);
    CHECK(measured_first_pass(3.99 / kGrowthMargin, lots) == 2);
    // From 4 rounds on, a net N with room for the pass to 2N.
    CHECK(measured_first_pass(4 / kGrowthMargin, lots) == 2);
    CHECK(measured_first_pass(7.9 / kGrowthMargin, lots) == 2);
    CHECK(measured_first_pass(8 / kGrowthMargin, lots) == 4);
    CHECK(measured_first_pass(100 / kGrowthMargin, lots) == 32);
    // A sample budget's rounds, all, where they fit: 5 rounds are no net.
    CHECK(measured_first_pass(10 / kGrowthMargin, 5) == 5);
    CHECK(measured_first_pass(1e30, 12) == 12);
    // Less than a round with the margin, nothing left, or no measure: none.
    CHECK(measured_first_pass(0.99 / kGrowthMargin, lots) == 0);
    CHECK(measured_first_pass(-3, lots) == 0);
    CHECK(measured_first_pass(std::nan(""), lots) == 0);
    CHECK(measured_first_pass(100, 0) == 0);
}

TEST_CASE("a round's cost: measures weighted by their rounds, earlier bakes' halved",
          "[bake][schedule]") {
    // Nothing earlier: this bake's measure.
    BlendedRoundCost b = blend_round_cost(0, 0, 0.019, 1);
    CHECK(b.seconds == Approx(0.019));
    CHECK(b.rounds == Approx(1));
    // A long bake's 32-round pass at 12 ms, then a one-round bake at 19 ms:
    // (19·1 + 12·16)/17.
    b = blend_round_cost(0.012, 32, 0.019, 1);
    CHECK(b.seconds == Approx((0.019 + 0.012 * 16) / 17));
    CHECK(b.rounds == Approx(17));
    // Bake after bake of one round, the measure moves to theirs.
    for (int k = 0; k < 12; ++k) b = blend_round_cost(b.seconds, b.rounds, 0.019, 1);
    CHECK(b.seconds == Approx(0.019).epsilon(0.01));
    CHECK(b.rounds < 2.1);
    // Equal rounds: the new measure weighs twice the earlier one.
    CHECK(blend_round_cost(0.010, 4, 0.016, 4).seconds == Approx((0.016 * 4 + 0.010 * 2) / 6));
    // No new measure: the earlier one, halved in weight.
    b = blend_round_cost(0.01, 8, 0, 0);
    CHECK(b.seconds == Approx(0.01));
    CHECK(b.rounds == Approx(4));
}

TEST_CASE("a pass's predicted cost: the first pass's fixed part plus the last pass's rate",
          "[bake][schedule]") {
    PassTimer timer;
    CHECK(timer.fit(1.0) == 0);  // nothing measured: nothing predicted
    timer.set_fixed(0.05);
    timer.add(4, 0.390);
    // A round costs (0.390 − 0.05)/4 s; 0.7 s fit (0.7 − 0.05)/0.085 rounds.
    CHECK(timer.fit(0.7) == Approx(0.65 / 0.085));
    // Two passes of 4 and 8 rounds with near-equal times (the shared
    // machine's load fell between them) predict from the last pass, not from
    // their slope, which put a round at 0.5 ms and let 48 rounds "fit" 0.7 s.
    timer.add(8, 0.392);
    CHECK(timer.fit(0.7) == Approx(0.65 / (0.342 / 8)));
    CHECK(timer.fit(0.7) < 16);
    // A fixed part beyond kMostFixed (3/4) of the last pass is capped there.
    timer.set_fixed(1.0);
    CHECK(timer.fit(0.7) == Approx((0.7 - 0.294) / (0.098 / 8)));
    // No fixed part measured: in proportion to the last pass.
    PassTimer proportional;
    proportional.add(2, 0.1);
    CHECK(proportional.fit(0.5) == Approx(10));
    CHECK(proportional.per_sample() == Approx(0.05));
    CHECK(PassTimer{}.per_sample() == 0);
}

TEST_CASE("a tail's weight: its rounds at α = 1, less where the error falls faster",
          "[bake][schedule]") {
    CHECK(tail_weight(32, 8, 1.0) == Approx(8));
    CHECK(tail_weight(32, 8, 2.0) == Approx(2));
    CHECK(tail_weight(32, 16, 3.0) == Approx(4));
}

TEST_CASE("NetRate recovers α from the changes of nested means", "[bake][schedule]") {
    // Changes between nested means: e(N0) − e(N1), with e(N) = C·N^-α.
    for (double alpha : {1.0, 1.5, 2.2, 2.9})
        for (const std::vector<int>& ends :
             {std::vector<int>{1, 2, 4, 8}, std::vector<int>{4, 16, 32}}) {
            NetRate rate;
            auto e = [&](int n) { return 3e-2 * std::pow(double(n), -alpha); };
            rate.add(ends[0], 0.0);
            for (std::size_t i = 1; i < ends.size(); ++i)
                rate.add(ends[i], e(ends[i - 1]) - e(ends[i]));
            INFO("alpha " << alpha << ", ends from " << ends[0]);
            CHECK(rate.measured());
            CHECK(rate.alpha() == Approx(alpha).epsilon(1e-6));
        }
    NetRate flat;  // changes that do not fall: independent draws at most
    flat.add(4, 0);
    flat.add(8, 1e-3);
    CHECK_FALSE(flat.measured());
    CHECK(flat.alpha() == 1.0);
    flat.add(16, 2e-3);
    CHECK(flat.measured());
    CHECK(flat.alpha() == 1.0);
    NetRate steep;  // beyond the range: kept at its top
    steep.add(4, 0);
    steep.add(8, 1.0);
    steep.add(16, 1e-6);
    CHECK(steep.alpha() == NetRate::kMaxAlpha);
}

TEST_CASE("a tail weighs by the measured α, else by one that never raises the error much",
          "[bake][schedule]") {
    NetRate rate;
    rate.add(1, 0);
    rate.add(8, 1e-2);  // one change (a pass that grew 8×): α unknown
    CHECK_FALSE(rate.measured());
    CHECK(rate.tail_alpha() == NetRate::kUnmeasuredAlpha);
    rate.add(16, 1e-2 * (std::pow(8.0, -1.5) - std::pow(16.0, -1.5)) /
                     (1 - std::pow(8.0, -1.5)));
    CHECK(rate.measured());
    CHECK(rate.tail_alpha() == rate.alpha());
    // The running mean of a net of N rounds (error v) and a tail of rN at
    // tail_weight's weights with the assumed α: its error (v + w²·v·r^-α) /
    // (1 + w)², w = r^a, against the net's alone, for scenes whose error
    // falls as N^-α with α from independent draws (1) to smooth light (2.5).
    auto joined = [](double r, double assumed, double alpha) {
        const double w = tail_weight(1 << 10, int(r * (1 << 10)), assumed) / (1 << 10);
        return (1 + w * w * std::pow(r, -alpha)) / ((1 + w) * (1 + w));
    };
    for (double r : {0.5, 0.25, 0.125, 0.0625})
        for (double alpha : {1.0, 1.5, 2.0, 2.5}) {
            INFO("tail " << r << "N, α " << alpha);
            CHECK(joined(r, NetRate::kUnmeasuredAlpha, alpha) < 1.013);
        }
    // Equal weights (α = 1 assumed) raise a smooth scene's error by half.
    CHECK(joined(0.25, 1.0, 2.2) > 1.4);
}

TEST_CASE("a time-budget bake ends on a power of two of rounds (plus tails) and stays "
          "unbiased", "[bake][schedule]") {
    std::vector<float> positions, uvs;
    std::vector<std::uint32_t> triangles;
    Scene scene;
    testing::two_triangle_floor(scene, positions, triangles, uvs);

    BakeSettings s;
    s.lighting.techniques = {*parse_technique("uniform/area")};
    s.lighting.samples = {1};
    s.lighting.rounds = 1 << 20;
    s.width = s.height = 8;
    // The mean over the floor's texels of (estimate − exact)/σ, σ the
    // estimate's reported noise (the independent-draw formula, an upper
    // bound of its true error: the test can only be stricter than 4σ).
    const UvCoverage cov = rasterize_uv(scene.geometry().mesh(0), s.width, s.height);
    for (double budget : {0.02, 0.1}) {
        s.time_budget = budget;
        const BakeResult r = bake(scene, s);
        INFO("budget " << budget);
        const std::uint32_t n = r.samples[0];
        const std::uint32_t net = std::uint32_t(power_of_two_floor(int(n)));
        CHECK(n - net < net);  // a net and tails smaller than it
        double sum_z = 0;
        std::size_t count = 0;
        for (std::size_t i = 0; i < r.samples.size(); ++i) {
            if (r.mask[i] <= 0) continue;
            CHECK(r.samples[i] == n);
            const double exact = testing::floor_lambert_footprint(scene, cov, i, 16);
            const double sigma = r.noise[i] * exact;
            REQUIRE(sigma > 0);
            sum_z += (r.value[3 * i] - exact) / sigma;
            ++count;
        }
        // 64 texels, each z within ±1 standard deviation of its error at most:
        // their mean is off by more than 4/√64 = 0.5 only for a bias.
        CHECK(std::abs(sum_z / double(count)) < 0.5);
    }
}

TEST_CASE("the halving fit leaves tail blocks out", "[bake][schedule]") {
    // Passes at error ∝ t^-0.75, then two tails whose error hardly moves: with
    // them the slope would flatten; without, β is the passes' own.
    std::vector<BakePassRecord> history;
    for (double t : {0.01, 0.04, 0.16, 0.64}) {
        BakePassRecord r;
        r.seconds = t;
        r.samples_per_texel = 100 * t;
        r.mean_relative_error = 0.1 * std::pow(t, -0.75);
        history.push_back(r);
    }
    for (double t : {0.8, 0.9}) {
        BakePassRecord r = history.back();
        r.seconds = t;
        r.samples_per_texel = 100 * t;
        r.tail = true;
        history.push_back(r);
    }
    const HalvingPrediction p = predict_halving(history);
    CHECK(p.measured());
    CHECK(p.beta == Approx(0.75).epsilon(1e-9));
    CHECK(p.seconds == Approx(0.9 * (std::pow(2.0, 1 / 0.75) - 1)).epsilon(1e-9));
}
