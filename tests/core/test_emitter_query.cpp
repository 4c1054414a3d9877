// GeometryScene::closest_hit_and_emitters (a light sample's query among
// emissive triangles, direct_lighting.cpp): closest_hit()'s hit, and lights
// EmitterShapes::lights_along lists — where only emitters lie along the ray
// and no emissive triangle is hit near its edge (`complete`), every one the
// ray crosses (an emissive mesh's triangles by their exact shape: they have
// no enlarged candidate there; other lights by their candidates), else at
// least those before the hit. Each light it appends is also handed to the
// caller's hook (ListedLight) at once.
#include <catch2/catch.hpp>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

#include "render/scene.h"
#include "support/emissive_sphere.h"

using namespace omis;

namespace {

std::vector<std::uint32_t> sorted_unique(std::vector<std::uint32_t> v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
}

// GeometryScene::ListedLight that keeps what it is told.
void keep_listed(void* kept, std::uint32_t light) {
    static_cast<std::vector<std::uint32_t>*>(kept)->push_back(light);
}

}  // namespace

TEST_CASE("closest_hit_and_emitters: closest_hit's hit and the lights along the ray",
          "[scene][emitters]") {
    // An emissive sphere, a second one inside its shadow, a square lamp above
    // them, a plate that does not emit over part of the floor.
    Scene scene;
    testing::add_emissive_sphere(scene, Vec3(0, 0, 1), 0.4, 8, 16);
    testing::add_emissive_sphere(scene, Vec3(0.1, 0, 2.2), 0.2, 6, 12);
    scene.set_mesh_lights(false);  // the query lists their triangles' lights
    scene.add_light(make_rect_light(Vec3(-0.3, -0.3, 1.6), Vec3(0, 0.6, 0), Vec3(0.6, 0, 0),
                                    Vec3(5, 5, 5), false, kPi));
    scene.add_mesh(std::vector<Vec3>{{0.2, -1, 0.3}, {1, -1, 0.3}, {1, 1, 0.3}, {0.2, 1, 0.3}},
                   {{0, 1, 2}, {0, 2, 3}});
    // An emissive strip with a degenerate triangle (no light) among its
    // own: its triangles' lights are not consecutive, so its hits name them
    // through GeometryScene's table, where the spheres' are computed.
    scene.add_mesh(std::vector<Vec3>{{-0.6, -0.5, 0.6}, {-0.1, -0.5, 0.6}, {-0.6, 0, 0.6},
                                     {-0.1, 0, 0.6}, {-0.6, 0.5, 0.6}, {-0.1, 0.5, 0.6},
                                     {-0.35, -0.5, 0.6}},
                   {{0, 1, 3}, {0, 3, 2}, {0, 6, 1}, {2, 3, 5}, {2, 5, 4}}, Vec3(2, 2, 2));
    scene.commit();
    const std::uint32_t strip = std::uint32_t(scene.geometry().num_meshes() - 1);
    REQUIRE(scene.geometry().mesh(strip).degenerate_triangles == 1);
    int strip_hits = 0;
    const GeometryScene& geometry = scene.geometry();
    REQUIRE(geometry.has_emitter_candidates());
    const double inf = std::numeric_limits<double>::infinity();
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    int complete_rays = 0, blocked_rays = 0, emissive_hits = 0, near_edge_rays = 0;
    for (int i = 0; i < 4000; ++i) {
        // From the floor toward a point of the spheres' region: most rays
        // meet emitters, some the plate first, some nothing.
        const Vec3 o(1.2 * u(rng), 1.2 * u(rng), 0);
        const Vec3 d = Vec3(0.5 * u(rng), 0.5 * u(rng), 1 + 1.2 * (u(rng) + 1)) - o;
        const auto expected = geometry.closest_hit(o, d, 0, inf);
        std::vector<std::uint32_t> lights, listed;
        bool complete = false;
        const auto hit =
            geometry.closest_hit_and_emitters(o, d, lights, complete, &keep_listed, &listed);
        INFO("ray " << i);
        REQUIRE(hit.has_value() == expected.has_value());
        CHECK(listed == lights);
        // (Whether the strip's lights are named right: the checks against
        // lights_along below, which finds them by their own shapes.)
        for (std::uint32_t l : lights) strip_hits += scene.lights()[l].mesh == strip ? 1 : 0;
        std::vector<std::uint32_t> along;
        scene.emitter_shapes().lights_along(o, d, along);
        along = sorted_unique(along);
        lights = sorted_unique(lights);
        if (hit) {
            CHECK(hit->t == expected->t);
            CHECK(hit->mesh == expected->mesh);
            CHECK(hit->triangle == expected->triangle);
            CHECK(hit->b1 == expected->b1);
            CHECK(hit->b2 == expected->b2);
            emissive_hits += geometry.mesh(hit->mesh).is_emissive() ? 1 : 0;
        }
        // A hit on a mesh that does not emit leaves the list short (and a
        // hit near an emissive triangle's edge, rarely).
        if (hit && !geometry.mesh(hit->mesh).is_emissive()) CHECK(!complete);
        CHECK(std::includes(along.begin(), along.end(), lights.begin(), lights.end()));
        if (complete) {
            ++complete_rays;
            for (std::uint32_t l : along) {
                const Light& light = scene.lights()[l];
                // Emissive triangles (two-sided) emit toward the ray's origin
                // wherever the ray crosses them exactly.
                if (light.mesh == ~0u || emitted_radiance(light, o, normalize(d)))
                    CHECK(std::binary_search(lights.begin(), lights.end(), l));
            }
            continue;
        }
        near_edge_rays += hit && geometry.mesh(hit->mesh).is_emissive() ? 1 : 0;
        ++blocked_rays;
        // Every light crossed before the hit is listed.
        for (std::uint32_t l : along) {
            const auto e = emitted_radiance(scene.lights()[l], o, normalize(d));
            if (e && e->distance < hit->t * length(d) * (1 - 1e-5))
                CHECK(std::binary_search(lights.begin(), lights.end(), l));
        }
    }
    CHECK(complete_rays > 1000);
    CHECK(blocked_rays > 200);
    CHECK(emissive_hits > 1000);
    CHECK(strip_hits > 200);
    // A hit within 1e-3 (in barycentrics) of an edge: ~0.6 % of a
    // triangle, a few hits per ray.
    CHECK(near_edge_rays < complete_rays / 20);
}
