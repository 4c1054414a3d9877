// The exact answer of the bake tests' floor: z = 0 under a 1 m square rect
// light at height 1 facing down, of radiance 2 (centred on the origin), at a
// point and averaged over a texel's footprint (the box filter a bake estimates).
#pragma once

#include <cstddef>

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

}  // namespace omis::testing
