// The unit square at z = 0 as a two-triangle mesh with per-corner UVs: what the
// UV-raster, margin and bake tests bake into.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/geometry_scene.h"

namespace omis::testing {

// Triangles A = (0,1,2) and B = (0,2,3), sharing the diagonal 0–2.
struct UnitSquare {
    std::vector<float> positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    std::vector<std::uint32_t> triangles = {0, 1, 2, 0, 2, 3};
    std::vector<float> uvs;  // 6 corners × (u, v), triangle by triangle

    // One UV island: the square laid onto [lo, hi]² of the UV plane.
    static UnitSquare island(float lo, float hi) {
        UnitSquare s;
        s.uvs = {lo, lo, hi, lo, hi, hi, lo, lo, hi, hi, lo, hi};
        return s;
    }
    // A view of the arrays for GeometryScene::add_mesh (this object keeps them).
    MeshInput input() const {
        MeshInput m;
        m.positions = ScalarArray::of(positions.data(), 4, 3);
        m.triangles = IndexArray{triangles.data(), 2, 3};
        m.uvs = ScalarArray::of(uvs.data(), 6, 2);
        return m;
    }
};

}  // namespace omis::testing
