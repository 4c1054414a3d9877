// A texel's table draws take the light point and the footprint position from
// one 4-D point of the light's own scrambled Sobol' sequence
// (direct_lighting.cpp, LightStreams; sequence.h, get_4d). The footprint's
// estimate must stay unbiased for the box-filtered irradiance where
// visibility depends on both (a penumbra crossing the footprint), in one call
// and over passes that continue the sequences, with and without MIS.
//
// T copies of one footprint (one texel id each: independent sequences) are T
// independent estimates; their mean must lie within 4 standard errors
// (measured from the copies) of the exact answer, a 6e-5 miss probability for
// a normal mean. Seeds are fixed, so the test is reproducible.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "render/direct_lighting.h"
#include "sampling/irradiance.h"
#include "support/square_footprint.h"

using namespace omis;
using omis::testing::SquareFootprint;

namespace {

constexpr double kSigmas = 4.0;

// Two one-sided square lights facing down at z = 1 and an opaque half-plane
// x ≥ 0 at z = 0.5. From a floor point (x, y, 0) the half-plane hides every
// light point of x-coordinate b ≥ −x (the ray to (b, y', 1) crosses z = 0.5 at
// (x + b)/2). Light A spans x ∈ [−0.5, 0.5]: seen up to b = −x. Light B spans
// x ∈ [0.5, 1.1]: hidden from the whole footprint (|x| ≤ 0.15), yet above its
// horizon, so `uniform` gives it half of the draws. With `dim_light`, a small
// dim light C over x ∈ [−1.5, −1.3], y ∈ [−0.1, 0.1], seen from every such point.
void add_scene(Scene& scene, bool dim_light = false) {
    scene.add_mesh(std::vector<Vec3>{{0, -50, 0.5}, {50, -50, 0.5}, {50, 50, 0.5}, {0, 50, 0.5}},
                   {{0, 1, 2}, {0, 2, 3}});
    scene.add_light(make_rect_light(Vec3(-0.5, -0.5, 1.0), Vec3(0, 1.0, 0), Vec3(1.0, 0, 0),
                                    Vec3(1, 1, 1), false, kPi));
    scene.add_light(make_rect_light(Vec3(0.5, -0.3, 1.0), Vec3(0, 0.6, 0), Vec3(0.6, 0, 0),
                                    Vec3(2, 2, 2), false, kPi));
    if (dim_light)
        scene.add_light(make_rect_light(Vec3(-1.5, -0.1, 1.0), Vec3(0, 0.2, 0), Vec3(0.2, 0, 0),
                                        Vec3(1, 1, 1), false, kPi));
    scene.commit();
}

// E/π averaged over the footprint (the box filter a texel bakes): the seen
// strip of light A at each point, and with `dim_light` all of C, by a 64²
// midpoint rule. The integrand is smooth over the 0.1 m square (the strip's
// edge moves with x), so the rule's error (~h² · f'' ≈ 1e-6 relative) is far
// below the copies' standard error.
double exact_over(const SquareFootprint& footprint, bool dim_light = false) {
    constexpr int n = 64;
    double sum = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const Vec3 x = footprint.at((i + 0.5) / n, (j + 0.5) / n).x;
            const double b = -x.x;  // light A is seen for b < −x
            sum += polygon_irradiance(x, Vec3(0, 0, 1),
                                      {{-0.5, -0.5, 1}, {b, -0.5, 1}, {b, 0.5, 1}, {-0.5, 0.5, 1}}) /
                   kPi;
            if (dim_light)
                sum += polygon_irradiance(
                           x, Vec3(0, 0, 1),
                           {{-1.5, -0.1, 1}, {-1.3, -0.1, 1}, {-1.3, 0.1, 1}, {-1.5, 0.1, 1}}) /
                       kPi;
        }
    return sum / (n * n);
}

DirectLightingSettings settings(std::vector<const char*> techniques, Strategy strategy) {
    DirectLightingSettings s;
    for (const char* t : techniques) {
        s.techniques.push_back(*parse_technique(t));
        s.samples.push_back(1);
    }
    s.strategy = strategy;
    s.seed = 11;
    return s;
}

void mean_and_variance(const std::vector<double>& v, double& mean, double& variance) {
    mean = 0;
    for (double x : v) mean += x / double(v.size());
    variance = 0;
    for (double x : v) variance += (x - mean) * (x - mean) / double(v.size() - 1);
}

}  // namespace

TEST_CASE("footprint table draws: unbiased in a penumbra, in one pass and over passes",
          "[strata][direct]") {
    Scene scene;
    add_scene(scene);
    const SquareFootprint footprint(Vec3(-0.1, 0, 0), 0.05);
    const double exact = exact_over(footprint);
    constexpr int kCopies = 2048;
    for (const auto& techniques : {std::vector<const char*>{"uniform/solid-angle"},
                                   std::vector<const char*>{"uniform/solid-angle", "bsdf"}})
        for (Strategy strategy : {Strategy::Balance, Strategy::OptimalDirect})
            for (bool passes : {false, true}) {
                LightingContext context(scene, settings(techniques, strategy));
                PointLighting shader(context);
                std::vector<double> copies;
                for (int c = 0; c < kCopies; ++c) {
                    double value[3], sum = 0;
                    if (passes) {  // [0, 8) then [8, 32), weighted by rounds as a bake does
                        shader.shade(std::uint64_t(c), 0, 8, footprint.centre(), &footprint, value,
                                     nullptr);
                        sum = 8 * value[1];
                        shader.shade(std::uint64_t(c), 8, 24, footprint.centre(), &footprint,
                                     value, nullptr);
                        copies.push_back((sum + 24 * value[1]) / 32);
                    } else {
                        shader.shade(std::uint64_t(c), 0, 32, footprint.centre(), &footprint,
                                     value, nullptr);
                        copies.push_back(value[1]);
                    }
                }
                double mean, variance;
                mean_and_variance(copies, mean, variance);
                const double standard_error = std::sqrt(variance / kCopies);
                INFO(techniques.size() << " technique(s), " << strategy_name(strategy)
                                       << (passes ? ", two passes" : ", one pass") << ": mean "
                                       << mean << ", exact " << exact << ", standard error "
                                       << standard_error);
                CHECK(std::isfinite(mean));
                CHECK(standard_error > 0);
                CHECK(std::abs(mean - exact) <= kSigmas * standard_error);
            }
}

namespace {

// shadowed_draws = 4 against none on `scene`: the footprint `shadowed` must
// draw differently (the probe fired) and stay unbiased for `exact` (the 4σ
// test of 2048 independent copies), in one pass and over two; `lit` must be
// shaded exactly as without the setting.
void check_shadowed_draws(const Scene& scene, const SquareFootprint& shadowed,
                          const SquareFootprint& lit, double exact) {
    constexpr int kCopies = 2048;
    auto shade = [&](PointLighting& shader, const SquareFootprint& footprint, std::uint64_t id,
                     bool passes) {
        double value[3];
        if (!passes) {
            shader.shade(id, 0, 16, footprint.centre(), &footprint, value, nullptr);
            return value[1];
        }
        shader.shade(id, 0, 4, footprint.centre(), &footprint, value, nullptr);
        const double first = 4 * value[1];
        shader.shade(id, 4, 12, footprint.centre(), &footprint, value, nullptr);
        return (first + 12 * value[1]) / 16;
    };
    for (Strategy strategy : {Strategy::Balance, Strategy::OptimalDirect})
        for (bool passes : {false, true}) {
            DirectLightingSettings s = settings({"uniform/solid-angle", "bsdf"}, strategy);
            DirectLightingSettings more = s;
            more.shadowed_draws = 4;
            LightingContext plain_context(scene, s), more_context(scene, more);
            PointLighting plain(plain_context), shader(more_context);
            std::vector<double> copies;
            for (int c = 0; c < kCopies; ++c)
                copies.push_back(shade(shader, shadowed, std::uint64_t(c), passes));
            double mean, variance;
            mean_and_variance(copies, mean, variance);
            const double standard_error = std::sqrt(variance / kCopies);
            INFO(strategy_name(strategy) << (passes ? ", two passes" : ", one pass") << ": mean "
                                         << mean << ", exact " << exact << ", standard error "
                                         << standard_error);
            CHECK(std::isfinite(mean));
            CHECK(standard_error > 0);
            CHECK(std::abs(mean - exact) <= kSigmas * standard_error);
            CHECK(shade(plain, shadowed, 7, passes) != shade(shader, shadowed, 7, passes));
            // A texel id no copy used: a texel's probe verdict is kept under its id.
            CHECK(shade(plain, lit, kCopies, passes) == shade(shader, lit, kCopies, passes));
        }
}

}  // namespace

// shadowed_draws: a footprint whose centre sees neither light's middle point
// draws 4 times each count a round, the choice fixed by that deterministic
// probe before any sample. Centred at x = 0.02 the middle (0, 0, 1) of light A
// is hidden (seen only for b < −0.02) while the footprint's part x < 0 sees a
// strip of A: the estimate must stay unbiased there. A footprint whose centre
// sees A's middle (x = −0.1; B's is hidden, but B brings less than A) is
// shaded exactly as without the setting.
TEST_CASE("shadowed_draws: more draws where the centre is shadowed, unbiased",
          "[strata][direct]") {
    Scene scene;
    add_scene(scene);
    const SquareFootprint shadowed(Vec3(0.02, 0, 0), 0.05), lit(Vec3(-0.1, 0, 0), 0.05);
    check_shadowed_draws(scene, shadowed, lit, exact_over(shadowed));
}

// The probe fires where the lights whose middles are hidden bring most of
// the light (kShadowedShare), not only where every middle is: with the dim
// light C seen from the whole footprint, at x = 0.02 the hidden middles of A
// and B still bring far more than half of what the three middle points
// bring unoccluded (the square's penumbra beside the box in shared_image).
TEST_CASE("shadowed_draws: more draws where the lights hidden at their middles bring most, "
          "unbiased",
          "[strata][direct]") {
    Scene scene;
    add_scene(scene, true);
    const SquareFootprint shadowed(Vec3(0.02, 0, 0), 0.05), lit(Vec3(-0.1, 0, 0), 0.05);
    check_shadowed_draws(scene, shadowed, lit, exact_over(shadowed, true));
}
