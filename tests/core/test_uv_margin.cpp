// Blender's "Adjacent Faces" margin (adjacent_margin_sources): texels beyond a UV
// seam take the value of the face across the seam in 3D; beyond a mesh boundary
// they extend as before.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "bake/uv_raster.h"
#include "support/unit_square.h"

using namespace omis;

namespace {

// A flat unit square (z = 0) of two triangles A = (0,1,2) and B = (0,2,3) sharing
// the diagonal 0–2, cut apart in UV: A at scale 0.3 near the origin, B rotated by
// 90° and moved away, so the diagonal is a seam. The other edges are boundaries.
struct SeamSquare {
    testing::UnitSquare square;
    GeometryScene scene;

    SeamSquare() {
        auto a = [](float x, float y) {
            return std::array<float, 2>{0.1f + 0.3f * x, 0.1f + 0.3f * y};
        };
        // Rotation (x, y) → (−y, x), then scale and offset.
        auto b = [](float x, float y) {
            return std::array<float, 2>{0.9f - 0.3f * y, 0.55f + 0.3f * x};
        };
        for (auto uv : {a(0, 0), a(1, 0), a(1, 1), b(0, 0), b(1, 1), b(0, 1)})
            square.uvs.insert(square.uvs.end(), uv.begin(), uv.end());
        scene.add_mesh(square.input());
    }
};

// The 3D point that triangle t's affine UV→3D map gives at texel coordinates
// (px, py) — also outside the triangle (its continuation across an edge).
Vec3 continued_position(const Mesh& mesh, std::uint32_t t, double px, double py,
                        int size) {
    const auto& u0 = mesh.corner_uvs[3 * t];
    const auto& u1 = mesh.corner_uvs[3 * t + 1];
    const auto& u2 = mesh.corner_uvs[3 * t + 2];
    const double x = px / size, y = py / size;
    const double d =
        (u1[0] - u0[0]) * (u2[1] - u0[1]) - (u2[0] - u0[0]) * (u1[1] - u0[1]);
    const double b1 = ((x - u0[0]) * (u2[1] - u0[1]) - (u2[0] - u0[0]) * (y - u0[1])) / d;
    const double b2 = ((u1[0] - u0[0]) * (y - u0[1]) - (x - u0[0]) * (u1[1] - u0[1])) / d;
    return mesh.position(t, b1, b2);
}

}  // namespace

TEST_CASE("adjacent-faces margin: across a seam from the face adjacent in 3D", "[bake]") {
    SeamSquare sq;
    const Mesh& mesh = sq.scene.mesh(0);
    const int size = 100, margin = 4;
    const UvCoverage c = rasterize_uv(mesh, size, size);
    const auto extend = margin_sources(c, margin);
    const auto adjacent = adjacent_margin_sources(c, mesh, margin);
    REQUIRE(adjacent.size() == extend.size());

    // One texel is 1/(0.3·100) of the square in 3D. The carried point lands within
    // half a texel diagonal (≈ 0.71 texel) of its texel's centre, which is where the
    // source's position is evaluated; 1.2 texels leaves room for rounding only.
    const double texel_3d = 1.0 / (0.3 * size);
    int across = 0;
    for (std::size_t i = 0; i < extend.size(); ++i) {
        INFO("texel " << i % size << "," << i / size);
        // The same texels are filled; covered ones are their own source.
        REQUIRE((adjacent[i] >= 0) == (extend[i] >= 0));
        if (c.is_covered(i)) {
            CHECK(adjacent[i] == std::int64_t(i));
            continue;
        }
        if (extend[i] < 0) continue;
        const std::uint32_t own = c.triangle[std::size_t(extend[i])];
        const std::uint32_t from = c.triangle[std::size_t(adjacent[i])];
        REQUIRE(from != kNoTriangle);
        if (from == own) {
            // Beyond a boundary edge (no face across): the Extend source.
            CHECK(adjacent[i] == extend[i]);
            continue;
        }
        // Across the seam: the source is where the island's face continues in 3D.
        ++across;
        const double px = double(i % size) + 0.5, py = double(i / size) + 0.5;
        const Vec3 want = continued_position(mesh, own, px, py, size);
        const std::size_t s = std::size_t(adjacent[i]);
        const Vec3 got = mesh.position(from, c.b1[s], c.b2[s]);
        CHECK(length(got - want) <= 1.2 * texel_3d);
    }
    // Both islands have a seam edge ~ 42 texels long with 4 rings beyond it: well
    // over a hundred texels come from across the seam (corners excepted).
    CHECK(across > 100);
}

TEST_CASE("adjacent-faces margin: a mesh without seams extends as before", "[bake]") {
    // The same square with one UV island: every border edge is a mesh boundary.
    const auto square = testing::UnitSquare::island(0.3f, 0.7f);
    GeometryScene scene;
    scene.add_mesh(square.input());
    const UvCoverage c = rasterize_uv(scene.mesh(0), 32, 32);
    for (int margin : {0, 1, 5})
        CHECK(adjacent_margin_sources(c, scene.mesh(0), margin) ==
              margin_sources(c, margin));
}
