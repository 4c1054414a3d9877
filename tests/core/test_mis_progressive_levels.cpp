// optimal-progressive with one scrambled sequence a point (issue 10): the level
// test must not throw away a correction its halves agree on
// (cross_fit_level_scale in mis/estimator.cpp).
//
// A small far rectangle light seen from a receiver beside it, sampled by
// power/solid-angle (6 a round) and bsdf (2): the bsdf technique seldom hits
// the light, so the balance estimate misses that technique's share in almost
// every run — skewed, about 2 reported σ low on average — while the
// control-variate correction restores it alike in every half of the
// sequence. The level test alone sees little half difference to explain and
// kept much of balance's error (python far receiver: rms 3.1 reported σ over
// 100 seeds, against 0.03 with the correction kept whole;
// tests/python/test_scene.py caught it).
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "render/direct_lighting.h"
#include "sampling/irradiance.h"
#include "support/lighting_settings.h"

using namespace omis;

TEST_CASE("optimal-progressive keeps a correction its sequence's halves agree on",
          "[mis][progressive]") {
    Scene scene;
    const Vec3 corner(-0.5, -0.25, 1), u(0, 0.5, 0), v(1, 0, 0);
    scene.add_light(make_rect_light(corner, u, v, Vec3(1, 1, 1), false, kPi));
    scene.commit();
    const Vec3 x(1.5, 0.5, 0), n(0, 0, 1);
    const double exact =
        polygon_irradiance(x, n, {corner, corner + u, corner + u + v, corner + v}) / kPi;

    constexpr int kCopies = 64;
    std::vector<double> points, normals;
    for (int i = 0; i < kCopies; ++i) {
        points.insert(points.end(), {x.x, x.y, x.z});
        normals.insert(normals.end(), {n.x, n.y, n.z});
    }
    auto squared_errors = [&](Strategy s) {
        const DirectLightingSettings settings =
            testing::lighting_settings({"power/solid-angle", "bsdf"}, {6, 2}, 16, s, 11);
        std::vector<double> value(3 * kCopies), variance(3 * kCopies);
        direct_lighting(scene, points.data(), normals.data(), kCopies, settings, value.data(),
                        variance.data());
        std::vector<double> e2(kCopies);
        for (int i = 0; i < kCopies; ++i) e2[i] = std::pow(value[3 * i + 1] - exact, 2);
        return e2;
    };
    const std::vector<double> balance = squared_errors(Strategy::Balance);
    const std::vector<double> progressive = squared_errors(Strategy::OptimalProgressive);
    // Paired, copy by copy: d = e²_prog − e²_bal / 4 has mean < 0 when the
    // kept correction removes at least three quarters of balance's MSE
    // (measured: MSE ratio 0.0003). Asserted with 3 standard errors of the
    // mean of d (fixed seeds); the level test alone measured 0.51 here and
    // fails.
    double mean = 0, var = 0;
    for (int i = 0; i < kCopies; ++i) mean += (progressive[i] - balance[i] / 4) / kCopies;
    for (int i = 0; i < kCopies; ++i) {
        const double d = progressive[i] - balance[i] / 4 - mean;
        var += d * d / (kCopies - 1);
    }
    double mse_balance = 0, mse_progressive = 0;
    for (int i = 0; i < kCopies; ++i) {
        mse_balance += balance[i] / kCopies;
        mse_progressive += progressive[i] / kCopies;
    }
    INFO("MSE ratio progressive/balance " << mse_progressive / mse_balance);
    CHECK(mean + 3 * std::sqrt(var / kCopies) < 0);
}
