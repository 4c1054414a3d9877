// The shortcuts of a light sample among emissive triangles
// (DirectLightingSettings::fast_paths, direct_lighting.cpp: integrand_to_blocker,
// add_unlit_sample): a sample whose drawn light is hidden lists only the
// lights up to its closest hit, and one whose integrand is then 0 skips the
// other lights' densities where the estimator does not use them. They must
// give the general path's estimates: the same samples, the same integrand
// values, and for a sample of integrand 0 the same sums (it adds 0 whatever
// the densities; with one technique the optimal moments hold p/q = 1/n).
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "render/direct_lighting.h"
#include "scene/emitter_shapes.h"
#include "support/emissive_sphere.h"
#include "support/lighting_settings.h"

using namespace omis;
using omis::testing::add_emissive_sphere;

namespace {

// issue 8's race scene in small: an emissive sphere with a square lamp above
// it (hidden by the sphere from the receivers below it), and an opaque plate
// that hides part of both from some receivers.
void build_scene(Scene& scene) {
    add_emissive_sphere(scene, Vec3(0, 0, 1), 0.4, 8, 16);
    scene.set_mesh_lights(false);  // its triangles as lights: the paths under test
    scene.add_light(make_rect_light(Vec3(-0.15, -0.15, 1.8), Vec3(0, 0.3, 0), Vec3(0.3, 0, 0),
                                    Vec3(20, 20, 20), false, kPi));
    scene.add_mesh(std::vector<Vec3>{{0.3, -1, 0.4}, {1, -1, 0.4}, {1, 1, 0.4}, {0.3, 1, 0.4}},
                   {{0, 1, 2}, {0, 2, 3}});
    scene.commit();
}

struct Bake {
    std::vector<double> value;
    DirectLightingStats stats;
};

Bake bake(const Scene& scene, DirectLightingSettings settings, bool fast_paths) {
    settings.fast_paths = fast_paths;
    std::vector<double> points, normals;
    for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 6; ++i) {
            points.insert(points.end(), {-1.2 + 0.48 * i, -1.2 + 0.48 * j, 0.0});
            normals.insert(normals.end(), {0.0, 0.0, 1.0});
        }
    Bake b;
    b.value.resize(points.size());
    b.stats = direct_lighting(scene, points.data(), normals.data(), points.size() / 3, settings,
                              b.value.data(), nullptr);
    return b;
}

// The same samples and integrand values: only the order in which a
// direction's lights are summed may differ, a few units of the last digit
// (1e-12 relative is ~5000 ulps).
void check_same_estimates(const Bake& fast, const Bake& general) {
    REQUIRE(fast.value.size() == general.value.size());
    for (std::size_t i = 0; i < fast.value.size(); ++i) {
        INFO("value " << i << ": " << fast.value[i] << " vs " << general.value[i]);
        CHECK(std::abs(fast.value[i] - general.value[i]) <=
              1e-12 * std::max(1.0, std::abs(general.value[i])));
    }
    CHECK(fast.stats.samples == general.stats.samples);
}

}  // namespace

TEST_CASE("emitter fast paths give the general path's estimates", "[direct][fast_paths]") {
    Scene scene;
    build_scene(scene);
    struct Case {
        std::vector<std::string> techniques;
        std::vector<int> samples;
        Strategy strategy;
        bool skips;  // whether samples of integrand 0 may skip their densities
    };
    const Case cases[] = {
        {{"tree/solid-angle"}, {8}, Strategy::OptimalDirect, true},
        {{"tree/solid-angle"}, {8}, Strategy::Balance, true},
        {{"tree/solid-angle", "bsdf"}, {6, 2}, Strategy::Balance, true},
        {{"tree/solid-angle", "bsdf"}, {6, 2}, Strategy::Power, true},
        {{"tree/solid-angle", "bsdf"}, {6, 2}, Strategy::OptimalDirect, false},
    };
    for (const Case& c : cases) {
        const DirectLightingSettings settings =
            testing::lighting_settings(c.techniques, c.samples, 4, c.strategy, 7);
        const Bake fast = bake(scene, settings, true), general = bake(scene, settings, false);
        INFO(c.techniques.size() << " techniques, " << strategy_name(c.strategy));
        check_same_estimates(fast, general);
        // Some receiver sees a hidden lamp: its samples skip the densities.
        if (c.skips)
            CHECK(fast.stats.pdf_evaluations < general.stats.pdf_evaluations);
        else
            CHECK(fast.stats.pdf_evaluations == general.stats.pdf_evaluations);
    }
}

// With a world (issue 9): every light's draw, and every BSDF direction,
// takes the closest hit first; lights without a shape (the world, a point
// light's disk) are judged by their distance to the blocker, and where nothing
// is hit and every shaped light is an emissive triangle, no emitter query is
// made. The same estimates as the general path.
TEST_CASE("emitter fast paths with a world give the general path's estimates",
          "[direct][fast_paths]") {
    // 0: emissive triangles, an occluder and a world (emission_world in
    // small); 1: the same and a point light of radius 5 cm (unshaped, local)
    // under the plate's edge; 2: the same and a square lamp (a shape not in
    // the geometry).
    for (int variant = 0; variant < 3; ++variant) {
        Scene scene;
        add_emissive_sphere(scene, Vec3(0, 0, 1), 0.4, 8, 16);
        scene.set_mesh_lights(false);  // its triangles as lights: the paths under test
        scene.add_mesh(
            std::vector<Vec3>{{0.3, -1, 0.4}, {1, -1, 0.4}, {1, 1, 0.4}, {0.3, 1, 0.4}},
            {{0, 1, 2}, {0, 2, 3}});
        scene.add_light(make_world_light(Vec3(0.3, 0.4, 0.5)));
        if (variant >= 1) scene.add_light(make_point_light(Vec3(0.5, 0.2, 0.3), Vec3(2, 2, 2), 0.05));
        if (variant >= 2)
            scene.add_light(make_rect_light(Vec3(-0.15, -0.15, 1.8), Vec3(0, 0.3, 0),
                                            Vec3(0.3, 0, 0), Vec3(20, 20, 20), false, kPi));
        scene.commit();
        const std::vector<std::string> names[] = {
            {"uniform/solid-angle", "bsdf"}, {"defensive/solid-angle"},
            {"defensive/solid-angle", "bsdf"}, {"tree/solid-angle", "bsdf"}};
        for (const auto& techniques : names)
            for (Strategy strategy : {Strategy::Balance, Strategy::OptimalDirect}) {
                const std::vector<int> samples(techniques.size(), 4);
                const DirectLightingSettings settings =
                    testing::lighting_settings(techniques, samples, 4, strategy, 11);
                const Bake fast = bake(scene, settings, true), general = bake(scene, settings, false);
                INFO("variant " << variant << ", " << techniques.front() << " and "
                                << techniques.size() - 1 << " more, " << strategy_name(strategy));
                check_same_estimates(fast, general);
            }
    }
}

TEST_CASE("emitter shapes: lights_along stops at tmax", "[scene][emitter_shapes]") {
    EmitterShapes shapes;
    // Two unit squares across the z axis, at z = 1 (light 4) and z = 3 (light 9).
    for (std::uint32_t light : {4u, 9u}) {
        const double z = light == 4 ? 1.0 : 3.0;
        shapes.add_triangle(light, {-1, -1, z}, {1, -1, z}, {1, 1, z});
        shapes.add_triangle(light, {-1, -1, z}, {1, 1, z}, {-1, 1, z});
    }
    shapes.commit();
    const Vec3 origin(0.2, 0.1, 0), up(0, 0, 1);
    std::vector<std::uint32_t> out;
    shapes.lights_along(origin, up, out);
    CHECK(out == std::vector<std::uint32_t>{4, 9});
    out.clear();
    shapes.lights_along(origin, up, out, 2.0);
    CHECK(out == std::vector<std::uint32_t>{4});
    out.clear();
    shapes.lights_along(origin, up, out, 0.5);
    CHECK(out.empty());
    // A light exactly at tmax is listed.
    out.clear();
    shapes.lights_along(origin, up, out, 1.0);
    CHECK(out == std::vector<std::uint32_t>{4});
}
