// The effect plan's light selection for several lights (2–16 integrated):
// uniform among local lights of comparable power, defensive otherwise, a
// world left to `bsdf`; and the plans' answers against exact ones where
// occlusion hides part of a light (the case uniform selection is chosen for)
// or of the world.
//
// The exact check lights kCopies copies of one receiver in one call: every
// copy draws from its own scrambled stream, so the copies are independent
// estimates. The mean must lie within 4 standard errors (measured from the
// copies) of the exact answer: a 6e-5 miss probability for a normal mean; the
// seed is fixed, so a pass is reproducible.
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

// The default plan's technique names. The scenes' lights are wide for their
// size, so the plan may add `bsdf` after the light technique (the huge-light
// rule); the selection is the first technique's.
using testing::plan_names;

// The plan's techniques at 8 samples a round, 4 rounds, over 64 copies of x:
// their mean within 4 of its standard errors of `exact` (a 6e-5 miss
// probability for a normal mean; fixed seeds), balance and optimal-progressive.
void check_plan_against_exact(const Scene& scene, const Vec3& x, const Vec3& n, double exact) {
    const std::vector<std::string> names = plan_names(scene);
    for (Strategy strategy : {Strategy::Balance, Strategy::OptimalProgressive}) {
        const testing::PointCopies e = testing::light_point_copies(
            scene, x, n, testing::lighting_settings(names, std::vector<int>(names.size(), 8), 4,
                                                 strategy, 7), 64);
        INFO(strategy_name(strategy) << ": " << e.mean << " ± " << e.standard_error
                                     << ", exact " << exact);
        CHECK(std::abs(e.mean - exact) <= 4.0 * e.standard_error);
    }
}

// A 1 m² ceiling light facing down at height h, its corner at (x0, y0).
Light ceiling_rect(double x0, double y0, double h, double radiance) {
    return make_rect_light(Vec3(x0, y0, h), Vec3(0, 1, 0), Vec3(1, 0, 0),
                           Vec3(radiance, radiance, radiance), false, kPi);
}

std::vector<Vec3> rect(const Vec3& corner, const Vec3& u, const Vec3& v) {
    return {corner, corner + u, corner + u + v, corner + v};
}

}  // namespace

TEST_CASE("the effect plan draws comparable local lights uniformly, others defensively",
          "[plan]") {
    // The selection the plan gives a scene of these lights alone.
    auto selection_for = [](const std::vector<Light>& lights) {
        Scene scene;
        for (const Light& light : lights) scene.add_light(light);
        scene.commit();
        return plan_names(scene).front();
    };
    CHECK(selection_for({ceiling_rect(-0.5, -0.5, 1, 2), ceiling_rect(1.0, -0.5, 1.5, 1)}) ==
          "uniform/solid-angle");  // powers 2:1
    CHECK(selection_for({ceiling_rect(-0.5, -0.5, 1, 9), ceiling_rect(1.0, -0.5, 1.5, 1)}) ==
          "defensive/solid-angle");  // powers 9:1
    CHECK(selection_for({ceiling_rect(-0.5, -0.5, 1, 1),
                         make_world_light(Vec3(0.001, 0.001, 0.001))}) ==
          "uniform/solid-angle");  // a world among the lights is bsdf's: one light left
    // A minor world (power 0.6 against 31 and 9) is bsdf's: the lamps decide.
    CHECK(selection_for({ceiling_rect(-0.5, -0.5, 1, 9), ceiling_rect(1.0, -0.5, 1.5, 1),
                         make_world_light(Vec3(0.01, 0.01, 0.01))}) ==
          "defensive/solid-angle");  // powers 9:1 besides the world
    CHECK(selection_for({ceiling_rect(-0.5, -0.5, 1, 2), ceiling_rect(1.0, -0.5, 1.5, 1),
                         make_world_light(Vec3(0.01, 0.01, 0.01))}) ==
          "uniform/solid-angle");  // powers 2:1 besides the world
    // The world as the main light (power 64 against 9) stays in the selection.
    CHECK(selection_for({ceiling_rect(-0.5, -0.5, 1, 2), ceiling_rect(1.0, -0.5, 1.5, 1),
                         make_world_light(Vec3(1, 1, 1))}) ==
          "defensive/solid-angle");
    CHECK(selection_for({ceiling_rect(-0.5, -0.5, 1, 1),
                         make_sun_light(Vec3(0, 0, -1), Vec3(1, 1, 1), 0.1)}) ==
          "defensive/solid-angle");  // a sun among the lights
    CHECK(selection_for({ceiling_rect(-0.5, -0.5, 1, 1), ceiling_rect(1.0, -0.5, 1.5, 1),
                         make_point_light(Vec3(0, 0, 2), Vec3(100, 100, 100), 0)}) ==
          "uniform/solid-angle");  // delta lights do not count
}

TEST_CASE("the uniform plan matches the exact answer under a half-hidden light", "[plan]") {
    // Two equal ceiling lights; an opaque half-plane (x ≥ 0 at z = 0.5) hides
    // the part of the first with x > 0.1 from x = (−0.1, 0, 0), and nothing of
    // the second (x ≤ −1.5).
    Scene scene;
    const Vec3 x(-0.1, 0, 0), n(0, 0, 1);
    scene.add_light(ceiling_rect(-0.5, -0.5, 1, 2));
    scene.add_light(ceiling_rect(-2.5, -0.5, 1.5, 2));
    scene.add_mesh(std::vector<Vec3>{{0, -50, 0.5}, {50, -50, 0.5}, {50, 50, 0.5}, {0, 50, 0.5}},
                   {{0, 1, 2}, {0, 2, 3}});
    scene.commit();
    const double exact =
        2 * (polygon_irradiance(x, n, rect({-0.5, -0.5, 1}, {0.6, 0, 0}, {0, 1, 0})) +
             polygon_irradiance(x, n, rect({-2.5, -0.5, 1.5}, {1, 0, 0}, {0, 1, 0}))) /
        kPi;
    REQUIRE(plan_names(scene).front() == "uniform/solid-angle");
    check_plan_against_exact(scene, x, n, exact);
}

namespace {

// The plan's techniques for `lights` and whether it leaves the world to bsdf,
// for the default techniques or the given ones.
struct WorldPlan {
    std::vector<std::string> names;
    bool world_by_bsdf = false;
};

WorldPlan world_plan(const std::vector<Light>& lights, const std::vector<std::string>& given = {}) {
    Scene scene;
    for (const Light& light : lights) scene.add_light(light);
    scene.commit();
    std::vector<Technique> techniques;
    std::vector<int> samples;
    if (given.empty()) {
        default_techniques(scene, techniques, samples);
    } else {
        for (const std::string& name : given) techniques.push_back(*parse_technique(name));
        samples.assign(techniques.size(), 1);
    }
    WorldPlan p;
    for (const Technique& t : techniques) p.names.push_back(t.name());
    p.world_by_bsdf = plan_effects(scene, techniques, samples).world_by_bsdf;
    return p;
}

}  // namespace

TEST_CASE("the effect plan leaves a minor world among few lights to bsdf", "[plan]") {
    // Power π²·0.05·R² = 0.5 (R = 1.01, the lamp's far corner) against the lamp's 2.5.
    const Light world = make_world_light(Vec3(0.05, 0.05, 0.05));
    // Small for the scene: the huge-light rule adds no bsdf of its own.
    const Light lamp = make_rect_light(Vec3(-0.1, -0.1, 1), Vec3(0, 0.2, 0), Vec3(0.2, 0, 0),
                                       Vec3(20, 20, 20), false, kPi);
    using Names = std::vector<std::string>;

    WorldPlan p = world_plan({lamp, world});
    CHECK(p.names == Names{"uniform/solid-angle", "bsdf"});
    CHECK(p.world_by_bsdf);
    // A world alone: the light technique's cosine sampling is bsdf's; one technique.
    p = world_plan({world});
    CHECK(p.names == Names{"uniform/solid-angle"});
    CHECK_FALSE(p.world_by_bsdf);
    // No bsdf among the given techniques: the light techniques keep the world.
    CHECK_FALSE(world_plan({lamp, world}, {"defensive/solid-angle"}).world_by_bsdf);
    CHECK(world_plan({lamp, world}, {"defensive/solid-angle", "bsdf"}).world_by_bsdf);
    // The tree's selector holds every light, the world too: no exception made.
    CHECK_FALSE(world_plan({lamp, world}, {"tree/solid-angle", "bsdf"}).world_by_bsdf);
    // A world BSDF rays cannot see stays with the light techniques.
    Light hidden = world;
    hidden.visible_to_bsdf = false;
    p = world_plan({lamp, hidden});
    CHECK(p.names == Names{"defensive/solid-angle"});
    CHECK_FALSE(p.world_by_bsdf);
    // A world that is the main light (power 10 against 2.5) keeps its draws
    // in the light technique's selection, bsdf or not.
    const Light bright = make_world_light(Vec3(1, 1, 1));
    p = world_plan({lamp, bright});
    CHECK(p.names == Names{"defensive/solid-angle"});
    CHECK_FALSE(p.world_by_bsdf);
    CHECK_FALSE(world_plan({lamp, bright}, {"defensive/solid-angle", "bsdf"}).world_by_bsdf);
    // Many lights: the tree plan, its selectors over every light.
    std::vector<Light> many{world};
    for (int i = 0; i <= kManyIntegratedLights; ++i) many.push_back(ceiling_rect(i, 0, 2, 1));
    p = world_plan(many);
    CHECK(p.names == Names{"tree/solid-angle", "bsdf"});  // the world by bsdf beside the tree
    CHECK_FALSE(p.world_by_bsdf);
}

TEST_CASE("a world left to bsdf keeps the exact answer where an occluder hides part of it",
          "[plan]") {
    // A 1 m² ceiling light over x and a world of radiance Lw; an opaque square
    // beside the light hides part of the world (and none of the light) from x.
    // Lambert receiver (albedo 1): E/π = (L·I_rect + Lw·(π − I_occluder))/π,
    // with I the cosine-weighted solid angles (polygon_irradiance).
    const double L = 2, Lw = 0.1;  // powers 2π and π²·Lw·R² = 2.7 (R = 1.66): minor
    const Vec3 x(-0.1, 0, 0), n(0, 0, 1);
    const std::vector<Vec3> occluder = rect({0.5, -0.5, 0.5}, {1, 0, 0}, {0, 1, 0});
    Scene scene;
    scene.add_light(ceiling_rect(-0.5, -0.5, 1, L));
    scene.add_light(make_world_light(Vec3(Lw, Lw, Lw)));
    scene.add_mesh(occluder, {{0, 1, 2}, {0, 2, 3}});
    scene.commit();
    const double exact =
        (L * polygon_irradiance(x, n, rect({-0.5, -0.5, 1}, {1, 0, 0}, {0, 1, 0})) +
         Lw * (kPi - polygon_irradiance(x, n, occluder))) /
        kPi;
    REQUIRE(plan_names(scene) == std::vector<std::string>{"uniform/solid-angle", "bsdf"});
    check_plan_against_exact(scene, x, n, exact);
}
