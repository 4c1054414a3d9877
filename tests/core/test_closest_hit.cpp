// GeometryScene::closest_hit (the shadow test's query): the same hit as
// intersect() — distance, mesh, triangle, barycentrics — without the surface.
#include <catch2/catch.hpp>

#include <limits>
#include <random>

#include "scene/geometry_scene.h"

using namespace omis;

TEST_CASE("closest_hit finds intersect's hit on random rays", "[scene]") {
    GeometryScene scene;
    // Two stacked quads and a tilted triangle: rays meet 0, 1 or several.
    scene.add_mesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}});
    scene.add_mesh({{0, 0, -1}, {1, 0, -1}, {1, 1, -1}, {0, 1, -1}}, {{0, 1, 2}, {0, 2, 3}});
    scene.add_mesh({{0.2, 0.2, 0.5}, {0.9, 0.3, 0.7}, {0.4, 0.8, 0.6}}, {{0, 1, 2}});
    scene.commit();
    const double inf = std::numeric_limits<double>::infinity();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-0.5, 1.5);
    int hits = 0, misses = 0;
    for (int i = 0; i < 2000; ++i) {
        const Vec3 o(u(rng), u(rng), 2), target(u(rng), u(rng), -2);
        const Vec3 d = target - o;
        const double tmin = i % 3 == 0 ? 0.3 : 0.0;  // some rays start past a surface
        const auto full = scene.intersect(o, d, tmin, inf);
        const auto bare = scene.closest_hit(o, d, tmin, inf);
        REQUIRE(full.has_value() == bare.has_value());
        if (!full) {
            ++misses;
            continue;
        }
        ++hits;
        CHECK(bare->t == full->t);
        CHECK(bare->mesh == full->mesh);
        CHECK(bare->triangle == full->triangle);
        CHECK(bare->b1 == full->b1);
        CHECK(bare->b2 == full->b2);
    }
    // The draw covers both outcomes.
    CHECK(hits > 100);
    CHECK(misses > 100);
}

TEST_CASE("closest_hit: the nearest surface, or none past tmax", "[scene]") {
    GeometryScene scene;
    const auto upper =
        scene.add_mesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}});
    const auto lower =
        scene.add_mesh({{0, 0, -1}, {1, 0, -1}, {1, 1, -1}, {0, 1, -1}}, {{0, 1, 2}, {0, 2, 3}});
    scene.commit();
    const Vec3 o(0.3, 0.6, 1), d(0, 0, -1);
    auto hit = scene.closest_hit(o, d, 0, 10);
    REQUIRE(hit);
    CHECK(hit->mesh == upper);
    CHECK(hit->t == Approx(1.0));
    hit = scene.closest_hit(o, d, 1.5, 10);  // starting below the upper quad
    REQUIRE(hit);
    CHECK(hit->mesh == lower);
    CHECK(hit->t == Approx(2.0));
    CHECK_FALSE(scene.closest_hit(o, d, 0, 0.9).has_value());
    CHECK_FALSE(scene.closest_hit({3, 3, 1}, d, 0, 10).has_value());
}
