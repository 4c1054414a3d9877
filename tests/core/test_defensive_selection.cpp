// `defensive` light selection (half unoccluded, half uniform over the lights
// that reach the point) against exact answers, alone and inside an MIS system.
//
// Each check lights kCopies copies of one receiver in one call: every copy
// draws from its own scrambled stream, so the copies are independent
// estimates. The mean must lie within 4 standard errors (measured from the
// copies) of the exact answer: a 6e-5 miss probability for a normal mean;
// the seeds are fixed, so a pass is reproducible.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "render/direct_lighting.h"
#include "render/effect_plan.h"
#include "sampling/irradiance.h"
#include "support/lighting_settings.h"
#include "support/point_copies.h"

using namespace omis;

namespace {

constexpr double kSigmas = 4.0;
constexpr int kCopies = 64;

testing::PointCopies light_copies(const Scene& scene, const Vec3& x, const Vec3& n,
                                  const std::vector<std::string>& names,
                                  const std::vector<int>& samples, Strategy strategy,
                                  std::uint64_t seed) {
    return testing::light_point_copies(
        scene, x, n, testing::lighting_settings(names, samples, 4, strategy, seed), kCopies);
}

std::vector<Vec3> rect(const Vec3& corner, const Vec3& u, const Vec3& v) {
    return {corner, corner + u, corner + u + v, corner + v};
}

// Two ceiling lights over the origin, the brighter one half hidden by an
// opaque half-plane (x ≥ 0 at z = 0.5: from (−0.1, 0, 0) its points with
// x > 0.1 are hidden), and a third light facing away (it reaches nothing):
// the case `unoccluded` weights get wrong and the uniform half covers.
struct ShadowedPair {
    Scene scene;
    Vec3 x{-0.1, 0, 0}, n{0, 0, 1};
    double exact = 0;

    ShadowedPair() {
        const Vec3 bright(-0.5, -0.5, 1), dim(-2.5, -0.5, 1.5), away(-0.5, 2, 1);
        scene.add_light(make_rect_light(bright, Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(4, 4, 4),
                                        false, kPi));
        scene.add_light(make_rect_light(dim, Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(1, 1, 1), false,
                                        kPi));
        scene.add_light(make_rect_light(away, Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(9, 9, 9), false,
                                        kPi));
        scene.add_mesh(
            std::vector<Vec3>{{0, -50, 0.5}, {50, -50, 0.5}, {50, 50, 0.5}, {0, 50, 0.5}},
            {{0, 1, 2}, {0, 2, 3}});
        scene.commit();
        // The occluder (x ≥ 0 at z = 0.5) hides nothing of the dim light (x ≤ −1.5).
        exact = (4 * polygon_irradiance(x, n, rect({-0.5, -0.5, 1}, {0.6, 0, 0}, {0, 1, 0})) +
                 polygon_irradiance(x, n, rect(dim, {1, 0, 0}, {0, 1, 0}))) /
                kPi;
    }
};

}  // namespace

TEST_CASE("defensive selection alone and with bsdf matches the exact answer", "[direct]") {
    const ShadowedPair s;
    struct Case {
        std::vector<std::string> names;
        std::vector<int> samples;
        Strategy strategy;
    };
    const Case cases[] = {
        {{"defensive/solid-angle"}, {8}, Strategy::Balance},
        {{"defensive/area"}, {8}, Strategy::Balance},
        {{"defensive/solid-angle", "bsdf"}, {4, 4}, Strategy::Balance},
        {{"defensive/solid-angle", "bsdf"}, {4, 4}, Strategy::OptimalProgressive},
        {{"defensive/solid-angle", "unoccluded/area"}, {4, 4}, Strategy::Balance},
    };
    std::uint64_t seed = 11;
    for (const Case& c : cases) {
        const testing::PointCopies e = light_copies(s.scene, s.x, s.n, c.names, c.samples, c.strategy, seed++);
        INFO(c.names[0] << (c.names.size() > 1 ? " + " + c.names[1] : "") << ", "
                        << strategy_name(c.strategy) << ": " << e.mean << " ± "
                        << e.standard_error << ", exact " << s.exact);
        CHECK(std::abs(e.mean - s.exact) <= kSigmas * e.standard_error);
    }
}

// A receiver under a ceiling with a skylight, lit by a world (the main light:
// drawn by cosine, its uniform share a tenth) and a small lamp under the
// ceiling: world_window in small. Exact: the world through the opening and
// past the ceiling's far edges, and the lamp (analytic lights occlude nothing).
TEST_CASE("defensive selection with a world through a skylight matches the exact answer",
          "[direct]") {
    const Vec3 x(0, 0, 0), n(0, 0, 1);
    const double Lw = 1.0, L = 5.0, z = 1.0, far = 50.0;
    const double x0 = 0.2, x1 = 0.6, y0 = -0.2, y1 = 0.2;  // the opening
    Scene scene;
    scene.add_light(make_world_light(Vec3(Lw, Lw, Lw)));
    const Vec3 lamp(-0.8, -0.15, 0.9);
    scene.add_light(make_rect_light(lamp, Vec3(0, 0.3, 0), Vec3(0.3, 0, 0), Vec3(L, L, L), false,
                                    kPi));
    // The ceiling around the opening: four rectangles.
    const std::vector<std::vector<Vec3>> ceiling = {
        rect({-far, -far, z}, {x0 + far, 0, 0}, {0, 2 * far, 0}),
        rect({x1, -far, z}, {far - x1, 0, 0}, {0, 2 * far, 0}),
        rect({x0, -far, z}, {x1 - x0, 0, 0}, {0, y0 + far, 0}),
        rect({x0, y1, z}, {x1 - x0, 0, 0}, {0, far - y1, 0})};
    for (const auto& r : ceiling) scene.add_mesh(r, {{0, 1, 2}, {0, 2, 3}});
    scene.commit();
    const double sky = kPi - polygon_irradiance(x, n, rect({-far, -far, z}, {2 * far, 0, 0},
                                                           {0, 2 * far, 0})) +
                       polygon_irradiance(x, n, rect({x0, y0, z}, {x1 - x0, 0, 0}, {0, y1 - y0, 0}));
    const double exact =
        (Lw * sky + L * polygon_irradiance(x, n, rect(lamp, {0.3, 0, 0}, {0, 0.3, 0}))) / kPi;
    const std::pair<std::vector<std::string>, std::vector<int>> cases[] = {
        {{"defensive/solid-angle"}, {8}}, {{"defensive/solid-angle", "bsdf"}, {4, 4}}};
    std::uint64_t seed = 23;
    for (const auto& [names, samples] : cases)
        for (Strategy strategy : {Strategy::Balance, Strategy::OptimalDirect}) {
            const testing::PointCopies e =
                light_copies(scene, x, n, names, samples, strategy, seed++);
            INFO(names.size() << " technique(s), " << strategy_name(strategy) << ": " << e.mean
                              << " ± " << e.standard_error << ", exact " << exact);
            CHECK(std::abs(e.mean - exact) <= kSigmas * e.standard_error);
        }
}

TEST_CASE("the effect plan samples a few lights with one defensive technique", "[direct]") {
    const ShadowedPair s;
    std::vector<Technique> techniques;
    std::vector<int> samples;
    default_techniques(s.scene, techniques, samples);
    REQUIRE(techniques.size() == 1);
    CHECK(techniques[0].name() == "defensive/solid-angle");
    CHECK(parse_technique("defensive/solid-angle") == techniques[0]);
}
