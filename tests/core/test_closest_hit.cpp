// GeometryScene::closest_hit (the shadow test's query): the same hit as
// intersect() — distance, mesh, triangle, barycentrics — without the surface.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

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

TEST_CASE("meshes as Embree quads: each hit is the triangle's, at its own barycentrics",
          "[scene]") {
    // A bumpy 12 × 12 grid (no cell planar), its cells' two triangles
    // written in every turn of their corners, in either order, split along
    // either diagonal, and in some cells wound against each other (those
    // stay two triangles). Traced as triangles and as quads, a ray away
    // from every edge hits the same triangle at the same barycentrics: a
    // wrong turn or half moves them by about the cell's size.
    constexpr int n = 12;
    std::vector<Vec3> p;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j)
            p.push_back({i / double(n), j / double(n), 0.03 * std::sin(7.0 * i + 3.0 * j * j)});
    std::vector<std::array<std::uint32_t, 3>> t;
    const auto turned = [](std::array<std::uint32_t, 3> c, int k) {
        return std::array<std::uint32_t, 3>{c[k % 3], c[(k + 1) % 3], c[(k + 2) % 3]};
    };
    for (int i = 0, cell = 0; i < n; ++i)
        for (int j = 0; j < n; ++j, ++cell) {
            const std::uint32_t v00 = i * (n + 1) + j, v10 = v00 + n + 1, v11 = v10 + 1,
                                v01 = v00 + 1;
            std::array<std::uint32_t, 3> a{v00, v10, v11}, b{v00, v11, v01};
            if (cell % 7 == 3) a = {v00, v10, v01}, b = {v10, v11, v01};
            if (cell % 11 == 5) b = {b[0], b[2], b[1]};  // wound against a
            a = turned(a, cell % 3);
            b = turned(b, (cell / 3) % 3);
            if (cell % 2) std::swap(a, b);
            t.push_back(a);
            t.push_back(b);
        }
    SceneOptions as_triangles, as_quads;
    as_triangles.quads = QuadMeshes::none;
    as_quads.quads = QuadMeshes::all;
    GeometryScene triangles(Device::shared(), as_triangles), quads(Device::shared(), as_quads);
    triangles.add_mesh(p, t);
    quads.add_mesh(p, t);
    triangles.commit();
    quads.commit();
    // Each cell a quad but the 13 wound against themselves: their 26
    // triangles are 13 to 26 quads (a pair may form across cells).
    CHECK(triangles.embree_quads(0) == 0);
    CHECK(quads.embree_quads(0) >= 131 + 13);
    CHECK(quads.embree_quads(0) <= 131 + 26);
    const double inf = std::numeric_limits<double>::infinity();
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-0.1, 1.1);
    int compared = 0, odd = 0;
    for (int k = 0; k < 4000; ++k) {
        const Vec3 o(u(rng), u(rng), 1), d = Vec3(u(rng), u(rng), -1) - o;
        const auto want = triangles.intersect(o, d, 0, inf);
        const auto got = quads.closest_hit(o, d, 0, inf);
        if (!want || std::min({want->b1, want->b2, 1 - want->b1 - want->b2}) < 1e-4) continue;
        INFO("ray " << k);
        REQUIRE(got);
        ++compared;
        if (got->triangle % 2 == 1) ++odd;
        CHECK(got->triangle == want->triangle);
        // Float rounding of Embree's u, v (the edges are 1/12 long).
        CHECK(std::abs(got->b1 - want->b1) < 1e-5);
        CHECK(std::abs(got->b2 - want->b2) < 1e-5);
        CHECK(std::abs(got->t - want->t) < 1e-5 * want->t);
        // The position a baker reads back is the one Embree found.
        CHECK(length(quads.mesh(0).position(got->triangle, got->b1, got->b2) - want->position) <
              1e-5);
    }
    CHECK(compared > 3000);
    CHECK(odd > 1000);  // both triangles of the cells are hit
}
