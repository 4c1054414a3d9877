// A closed emissive UV sphere: the many-emitter scenes of the emitter tests
// and bench/bench_emitters.cpp.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "lights/light.h"
#include "render/scene.h"

namespace omis::testing {

// `stacks`×`slices` quads (caps as triangles): 2·slices·(stacks − 1)
// triangles, outward winding, emitting `radiance` (W/(m² sr)).
inline void add_emissive_sphere(Scene& scene, const Vec3& centre, double radius, int stacks,
                                int slices, const Vec3& radiance = Vec3(1, 1, 1)) {
    std::vector<Vec3> p{centre + Vec3(0, 0, radius)};
    for (int i = 1; i < stacks; ++i)
        for (int j = 0; j < slices; ++j) {
            const double theta = kPi * i / stacks, phi = 2 * kPi * j / slices;
            p.push_back(centre + radius * Vec3(std::sin(theta) * std::cos(phi),
                                               std::sin(theta) * std::sin(phi),
                                               std::cos(theta)));
        }
    p.push_back(centre - Vec3(0, 0, radius));
    const auto ring = [&](int i, int j) {
        return std::uint32_t(1 + (i - 1) * slices + (j % slices));
    };
    const std::uint32_t bottom = std::uint32_t(p.size() - 1);
    std::vector<std::array<std::uint32_t, 3>> t;
    for (int j = 0; j < slices; ++j) {
        t.push_back({0, ring(1, j), ring(1, j + 1)});
        t.push_back({bottom, ring(stacks - 1, j + 1), ring(stacks - 1, j)});
        for (int i = 1; i + 1 < stacks; ++i) {
            t.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
            t.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
        }
    }
    scene.add_mesh(p, t, radiance);
}

// bench_cycles.py's emissive_mesh race scene (tests/blender/cycles_scenes.py)
// without its receiver: a UV sphere of 128 × 64 segments (16,128 triangles,
// radius 0.3 at (0.2, 0.1, 0.6), Blender's emission 3 × (1, 0.85, 0.7)) under
// a 0.3 m square light of 40 W at 1.4 m, emitting down (radiance P/(4A), as
// omis.blender_units.area_light).
inline void add_race_mesh(Scene& scene) {
    add_emissive_sphere(scene, Vec3(0.2, 0.1, 0.6), 0.3, 64, 128, Vec3(3.0, 2.55, 2.1));
    scene.add_light(make_rect_light(Vec3(0.2, 0.05, 1.4), Vec3(0, 0.3, 0), Vec3(0.3, 0, 0),
                                    Vec3(1, 1, 1) * (40.0 / (4.0 * 0.09)), false, kPi));
}

}  // namespace omis::testing
