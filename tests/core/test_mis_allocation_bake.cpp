// Sample allocation in bakes (issue 10, item 2; BakeSettings::allocate_samples):
// later passes continue each technique's sequence whatever their counts, the
// result stays unbiased against the exact answer, and the same seed gives the
// same bits at any thread count.
#include <catch2/catch.hpp>

#include <tbb/global_control.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "bake/bake.h"
#include "bake/uv_raster.h"
#include "sampling/irradiance.h"
#include "support/floor_lambert.h"
#include "support/lighting_settings.h"

using namespace omis;

namespace {

// A 2 m floor quad (z = 0, UV = its xy in [0,1]²) under a 1 m rect light at
// height 1 facing down, of radiance 2: E/π at x is 2·polygon_irradiance/π.
void floor_scene(Scene& scene) {
    static const float positions[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    static const std::uint32_t triangles[] = {0, 1, 2, 0, 2, 3};
    static const float uvs[] = {0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1};
    MeshInput m;
    m.name = "floor";
    m.positions = ScalarArray::of(positions, 4, 3);
    m.triangles = IndexArray{triangles, 2, 3};
    m.uvs = ScalarArray::of(uvs, 6, 2);
    scene.add_mesh(m);
    scene.add_light(make_rect_light(Vec3(-0.5, -0.5, 1), Vec3(0, 1, 0), Vec3(1, 0, 0),
                                    Vec3(2, 2, 2), false, kPi));
    scene.commit();
}

double lambert_footprint(const Scene& scene, const UvCoverage& cov, std::size_t i) {
    return testing::floor_lambert_footprint(scene, cov, i, 16);
}

BakeSettings allocated_settings(Strategy strategy) {
    BakeSettings s;
    s.lighting = testing::lighting_settings({"uniform/solid-angle", "uniform/area", "bsdf"},
                                            {1, 1, 1}, 1, strategy, 11);
    s.samples = 96;  // 32 rounds: a pilot of 8, then 24 rounds' samples allocated
    s.width = s.height = 32;
    s.margin = 0;
    s.allocate_samples = true;
    return s;
}

}  // namespace

TEST_CASE("allocation: a bake stays unbiased against the exact answer", "[bake][mis]") {
    Scene scene;
    floor_scene(scene);
    const UvCoverage cov = rasterize_uv(scene.geometry().mesh(0), 32, 32);
    std::vector<double> exact(cov.triangle.size());
    for (std::size_t i = 0; i < exact.size(); ++i)
        if (cov.is_covered(i)) exact[i] = lambert_footprint(scene, cov, i);
    for (Strategy strategy : {Strategy::OptimalProgressive, Strategy::OptimalDirect}) {
        const BakeResult r = bake(scene, allocated_settings(strategy));
        INFO(strategy_name(strategy) << ": " << r.stats.allocation);
        REQUIRE(r.stats.allocated_shares.size() == 3);
        // Every texel took exactly the asked samples, and every technique kept
        // its floor; solid angle is the best single technique under an
        // unoccluded rect, so the allocation leans to it.
        CHECK(r.stats.samples == 96u * r.stats.covered);
        CHECK(std::accumulate(r.stats.allocated_shares.begin(), r.stats.allocated_shares.end(),
                              0.0) == Approx(1.0));
        for (double w : r.stats.allocated_shares) CHECK(w >= 0.05 - 1e-9);
        CHECK(r.stats.allocated_shares[0] > 1.0 / 3);
        double sum_err = 0, sum_var = 0;
        int beyond = 0, n = 0;
        for (std::size_t i = 0; i < exact.size(); ++i) {
            if (!cov.is_covered(i)) continue;
            const double err = r.value[3 * i + 1] - exact[i];
            const double sd = r.noise[i] * r.value[3 * i + 1];
            sum_err += err;
            sum_var += sd * sd;
            beyond += std::abs(err) > 4 * sd;
            ++n;
        }
        // At most 1 % of texels beyond 4σ̂ (a normal tail holds 6e-5; σ̂ per
        // texel is itself noisy).
        CHECK(beyond <= n / 100);
        const double standard_error = std::sqrt(sum_var) / n;  // of the image's mean error
        if (strategy == Strategy::OptimalProgressive) {
            // Unbiased: the mean error over the image within 4 standard
            // errors. An allocation that reused or skipped sequence points,
            // or weighted passes wrongly, shifts it.
            CHECK(std::abs(sum_err / n) <= 4 * standard_error);
        } else {
            // optimal-direct is consistent, not unbiased: α fitted to a pass's
            // own samples leaves an O(1/samples) bias, and the allocated bake
            // solves the pilot's 24 samples apart. Bound: a quarter of one
            // texel's σ (σ̂ ≈ standard_error·√n), beside which it adds ≤ 6 %
            // to the MSE; a broken allocation shifts the mean by far more.
            CHECK(std::abs(sum_err / n) <= 4 * standard_error + 0.25 * standard_error * std::sqrt(n));
        }
    }
}

TEST_CASE("allocation: the same seed gives the same bits at any thread count", "[bake][mis]") {
    Scene scene;
    floor_scene(scene);
    BakeSettings s = allocated_settings(Strategy::OptimalDirect);
    s.samples = 50;  // 15 rounds of 3 (a pilot of 3), then a final round of 5, allocated too
    BakeResult one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = bake(scene, s);
    }
    const BakeResult all = bake(scene, s);
    CHECK(one.value == all.value);
    CHECK(one.noise == all.noise);
    CHECK(one.stats.allocation == all.stats.allocation);
    CHECK(one.stats.samples == 50u * one.stats.covered);
    // And the allocation changed something: the fixed-count bake differs.
    s.allocate_samples = false;
    CHECK(bake(scene, s).value != one.value);
}

TEST_CASE("allocation: a later call continues every technique's sequence", "[mis]") {
    // One technique, balance: a point's estimate is the plain mean of its
    // draws, so rounds [0, 8) with 2 draws each in one call equal the
    // sample-weighted mean of [0, 4) and [4, 8) in two calls — when the second
    // call starts after the first one's draws (earlier). Without it, the
    // second call would start where 1 draw a round (the settings' count)
    // would have left the sequence, repeat draws, and differ.
    Scene scene;
    floor_scene(scene);
    const LightingContext context(
        scene, testing::lighting_settings({"uniform/area"}, {1}, 8, Strategy::Balance, 3));
    PointLighting shader(context);
    const SurfacePoint p{Vec3(0.3, -0.2, 0), Vec3(0, 0, 1), Vec3(0, 0, 1)};
    const int two[1] = {2};
    double whole[3], first[3], second[3], repeated[3];
    shader.shade(5, 0, 8, p, nullptr, whole, nullptr, two);
    shader.shade(5, 0, 4, p, nullptr, first, nullptr, two);
    const std::vector<DrawnRounds> earlier = {{0, 4, two}};
    shader.shade(5, 4, 4, p, nullptr, second, nullptr, two, nullptr, nullptr, &earlier);
    shader.shade(5, 4, 4, p, nullptr, repeated, nullptr, two);
    CHECK((first[1] + second[1]) / 2 == Approx(whole[1]).epsilon(1e-12));
    CHECK((first[1] + repeated[1]) / 2 != Approx(whole[1]).epsilon(1e-6));
    const std::vector<DrawnRounds> gap = {{0, 3, two}};
    CHECK_THROWS_WITH(
        shader.shade(5, 4, 4, p, nullptr, second, nullptr, two, nullptr, nullptr, &gap),
        Catch::Contains("earlier"));
}

TEST_CASE("allocation: a noise-target bake (several streams) stays unbiased", "[bake][mis]") {
    // Under a noise target a point's rounds go to several streams whose
    // tallies measure the error; allocated passes deal their own rounds to
    // them. The image's mean error must stay within 4 of its standard errors
    // (optimal-progressive is unbiased), and the bake must end on its target.
    Scene scene;
    floor_scene(scene);
    const UvCoverage cov = rasterize_uv(scene.geometry().mesh(0), 32, 32);
    BakeSettings s = allocated_settings(Strategy::OptimalProgressive);
    s.samples = 0;
    s.lighting.rounds = 1 << 12;
    s.noise_target = 0.02;
    s.lighting.streams = 4;
    const BakeResult r = bake(scene, s);
    INFO(r.stats.allocation);
    CHECK(r.stats.status == BakeStatus::NoiseTarget);
    CHECK(r.stats.allocated_shares.size() == 3);
    double sum_err = 0, sum_var = 0;
    int n = 0;
    for (std::size_t i = 0; i < cov.triangle.size(); ++i) {
        if (!cov.is_covered(i)) continue;
        const double sd = r.noise[i] * r.value[3 * i + 1];
        sum_err += r.value[3 * i + 1] - lambert_footprint(scene, cov, i);
        sum_var += sd * sd;
        ++n;
    }
    CHECK(std::abs(sum_err / n) <= 4 * std::sqrt(sum_var) / n);
}
