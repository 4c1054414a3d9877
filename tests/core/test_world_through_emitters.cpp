// A minor constant world among emissive triangles is seen through them
// (EffectPlan::world_through_emitters, direct_lighting.cpp split_world,
// split_parts): the world's part L_w wherever no surface that does not emit is
// hit first, estimated by `bsdf` alone, and the emitters' part L_e − L_w, by
// the light techniques alone. The two parts sum to the integrand at every
// direction, so the estimate must stay that of E/π.
//
// As in test_own_light_estimates.cpp: T copies of one receiver in one call
// are T independent estimates; their mean must lie within 4 standard errors
// (measured from the copies) of the exact answer, a 6e-5 miss probability for
// a normal mean; the seeds are fixed.
#include <catch2/catch.hpp>

#include <cmath>
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

using Quad = std::vector<Vec3>;
// emission_world in small (tests/blender/cycles_scenes.py): a 0.6 m emissive
// square 0.7 m up, and an opaque plate 0.35 m up beside it.
const Quad kEmitter = {{-0.1, -0.3, 0.7}, {0.5, -0.3, 0.7}, {0.5, 0.3, 0.7}, {-0.1, 0.3, 0.7}};
const Quad kPlate = {{-0.8, -0.3, 0.35}, {-0.3, -0.3, 0.35}, {-0.3, 0.3, 0.35}, {-0.8, 0.3, 0.35}};

void build(Scene& scene, double emitter_radiance, double world_radiance) {
    scene.add_mesh(kEmitter, {{0, 2, 1}, {0, 3, 2}}, Vec3(1, 1, 1) * emitter_radiance);
    scene.add_mesh(kPlate, {{0, 1, 2}, {0, 2, 3}});
    scene.add_light(make_world_light(Vec3(1, 1, 1) * world_radiance));
    scene.commit();
}

// E/π at x (normal +z): the world where neither the emitter nor the plate
// lies, the emitter where it does. From the points below, the plate and the
// emitter do not overlap (they meet at most along an edge: measure zero).
double exact(const Vec3& x, double emitter_radiance, double world_radiance) {
    const Vec3 up(0, 0, 1);
    const double emitter = polygon_irradiance(x, up, kEmitter) / kPi;
    const double plate = polygon_irradiance(x, up, kPlate) / kPi;
    return world_radiance * (1 - emitter - plate) + emitter_radiance * emitter;
}

// The plan's default techniques at x, balance and optimal-direct: the mean of
// the copies within kSigmas standard errors of `expected`.
void check_unbiased(const Scene& scene, const Vec3& x, double expected, std::uint64_t seed) {
    std::vector<Technique> techniques;
    std::vector<int> samples;
    default_techniques(scene, techniques, samples);
    for (Strategy s : {Strategy::Balance, Strategy::OptimalDirect}) {
        DirectLightingSettings settings;
        settings.techniques = techniques;
        settings.samples = samples;
        settings.rounds = 8;
        settings.strategy = s;
        settings.seed = seed;
        const testing::PointCopies e =
            testing::light_point_copies(scene, x, Vec3(0, 0, 1), settings, kCopies);
        INFO("x = (" << x.x << ", " << x.y << "), " << strategy_name(s) << ", mean " << e.mean
                     << ", expected " << expected << ", σ " << e.standard_error);
        CHECK(e.finite);
        CHECK(std::abs(e.mean - expected) <= kSigmas * e.standard_error);
    }
}

}  // namespace

TEST_CASE("a minor world seen through emissive triangles: the plan", "[direct][world]") {
    Scene scene;
    build(scene, 6.0, 0.2);
    std::vector<Technique> techniques;
    std::vector<int> samples;
    default_techniques(scene, techniques, samples);
    const EffectPlan plan = plan_effects(scene, techniques, samples);
    CHECK(plan.world_by_bsdf);
    CHECK(plan.world_through_emitters);
    // Without `bsdf` the world is the light technique's, drawn as a light.
    const std::vector<Technique> lights_only = {*parse_technique("uniform/solid-angle")};
    CHECK_FALSE(plan_effects(scene, lights_only, {1}).world_through_emitters);
}

TEST_CASE("an emitter dimmer than the world is not seen through", "[direct][world]") {
    // The emitters' part L_e − L_w would be negative: the plan keeps the
    // world behind the emitter (where it stays a minor light).
    Scene scene;
    scene.add_mesh(kEmitter, {{0, 2, 1}, {0, 3, 2}}, Vec3(6, 6, 0.1));
    scene.add_light(make_world_light(Vec3(0.2, 0.2, 0.2)));
    scene.commit();
    const std::vector<Technique> techniques = {*parse_technique("uniform/solid-angle"),
                                               *parse_technique("bsdf")};
    const EffectPlan plan = plan_effects(scene, techniques, {1, 1});
    CHECK(plan.world_by_bsdf);
    CHECK_FALSE(plan.world_through_emitters);
}

TEST_CASE("a minor world seen through emissive triangles: unbiased", "[direct][world]") {
    const double emitter = 6.0, world = 0.2;
    Scene scene;
    build(scene, emitter, world);
    // Under the emitter; beside it (the plate hides part of the world); under
    // the plate, next to the emitter's edge.
    for (const Vec3& x : {Vec3(0.2, 0, 0), Vec3(0.6, 0.2, 0), Vec3(-0.5, 0, 0)})
        check_unbiased(scene, x, exact(x, emitter, world), 5);
}

TEST_CASE("a minor world seen through emissive triangles around a closed box: unbiased",
          "[direct][world]") {
    // The plan's occluder draws (EffectPlan::world_occluders) toward a closed
    // box of 12 triangles, whose hidden faces (top, far sides) are in its
    // bounding box too: a draw toward one of them sees the near face first.
    // Exact: the box faces turned toward x hide the world where they lie
    // (a convex box: they do not overlap), and from these points the box
    // and the emitter do not overlap either (rays to the emitter pass
    // x > −0.4 below z = 0.4; rays to the box reach z = 0.7 far from it).
    const double emitter = 6.0, world = 0.2;
    const Vec3 lo(-0.8, -0.2, 0.3), hi(-0.4, 0.2, 0.4);
    Scene scene;
    scene.add_mesh(kEmitter, {{0, 2, 1}, {0, 3, 2}}, Vec3(1, 1, 1) * emitter);
    std::vector<Vec3> corners;
    for (int i = 0; i < 8; ++i)
        corners.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
    scene.add_mesh(corners, {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}});
    scene.add_light(make_world_light(Vec3(1, 1, 1) * world));
    scene.commit();
    std::vector<Technique> techniques;
    std::vector<int> samples;
    default_techniques(scene, techniques, samples);
    REQUIRE(plan_effects(scene, techniques, samples).world_occluders.size() == 1);
    const Vec3 up(0, 0, 1);
    auto box_faces_seen = [&](const Vec3& x) {
        double e = 0;
        const double p[3] = {x.x, x.y, x.z}, l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
        for (int a = 0; a < 3; ++a) {
            if (l[a] <= p[a] && p[a] <= h[a]) continue;
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            std::vector<Vec3> quad;
            for (int k = 0; k < 4; ++k) {
                double q[3];
                q[a] = p[a] < l[a] ? l[a] : h[a];
                q[b] = (k == 1 || k == 2) ? h[b] : l[b];
                q[c] = k >= 2 ? h[c] : l[c];
                quad.push_back({q[0], q[1], q[2]});
            }
            e += polygon_irradiance(x, up, quad) / kPi;
        }
        return e;
    };
    // Under the box; beside it (x and y faces seen too); under the emitter.
    for (const Vec3& x : {Vec3(-0.6, 0.05, 0), Vec3(-0.3, 0.5, 0), Vec3(0.2, 0, 0)}) {
        const double e = polygon_irradiance(x, up, kEmitter) / kPi;
        check_unbiased(scene, x, world * (1 - e - box_faces_seen(x)) + emitter * e, 7);
    }
}
