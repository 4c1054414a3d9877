// The exact answer of the bake tests' floor: z = 0 under a 1 m square rect
// light at height 1 facing down, of radiance 2 (centred on the origin), at a
// point and averaged over a texel's footprint (the box filter a bake estimates).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "bake/uv_raster.h"
#include "render/scene.h"
#include "sampling/irradiance.h"

namespace omis::testing {

// E/π at x on the floor (normal +z): 2·polygon_irradiance/π.
inline double floor_lambert(const Vec3& x) {
    return 2 * polygon_irradiance(x, Vec3(0, 0, 1),
                                  {{-0.5, -0.5, 1}, {0.5, -0.5, 1}, {0.5, 0.5, 1}, {-0.5, 0.5, 1}}) /
           kPi;
}

// floor_lambert averaged over texel i's footprint of mesh 0, by an n × n
// midpoint rule over the footprint's (u, v) square.
inline double floor_lambert_footprint(const Scene& scene, const UvCoverage& cov, std::size_t i,
                                      int n = 32) {
    const Mesh& mesh = scene.geometry().mesh(0);
    const TexelFootprintMap map(mesh, cov, i);
    double sum = 0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const auto bc = map.barycentrics((a + 0.5) / n, (b + 0.5) / n);
            sum += floor_lambert(mesh.position(map.triangle(), bc[0], bc[1]));
        }
    return sum / (n * n);
}

// Four corners (positions, 4 × 3), two triangles and their corners' UVs
// (6 × 2) as a mesh; the arrays must outlive the scene it is added to.
inline MeshInput two_triangle_mesh(const char* name, const std::vector<float>& positions,
                                   const std::vector<std::uint32_t>& triangles,
                                   const std::vector<float>& uvs) {
    MeshInput m;
    m.name = name;
    m.positions = ScalarArray::of(positions.data(), 4, 3);
    m.triangles = IndexArray{triangles.data(), 2, 3};
    m.uvs = ScalarArray::of(uvs.data(), 6, 2);
    return m;
}

// The floor alone: a 2 m square of two triangles (UVs over [0,1]²) under that
// light, committed. The arrays must outlive the scene (it reads them in place).
inline void two_triangle_floor(Scene& scene, std::vector<float>& positions,
                               std::vector<std::uint32_t>& triangles, std::vector<float>& uvs) {
    positions = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    triangles = {0, 1, 2, 0, 2, 3};
    uvs.clear();
    for (std::uint32_t i : triangles)
        uvs.insert(uvs.end(), {0.5f * (positions[3 * i] + 1), 0.5f * (positions[3 * i + 1] + 1)});
    scene.add_mesh(two_triangle_mesh("floor", positions, triangles, uvs));
    scene.add_light(make_rect_light(Vec3(-0.5, -0.5, 1), Vec3(0, 1, 0), Vec3(1, 0, 0),
                                    Vec3(2, 2, 2), false, kPi));
    scene.commit();
}

}  // namespace omis::testing
