// The shapes of area lights (rects, ellipses, emissive mesh triangles) in an
// Embree scene of their own, so that a direction finds the lights it crosses
// without a loop over every light. The shapes are slightly enlarged
// candidates: callers confirm each light exactly (emitted_radiance,
// light_pdf), so a ray grazing an edge in single precision is never missed.
// Kept apart from the occluder scene: lights do not occlude (SPEC §3). (A
// copy of the shapes that are not emissive meshes' triangles also rides in
// the occluder scene under its own ray mask, for light samples' single
// traversal: GeometryScene::closest_hit_and_emitters.)
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "math/vec3.h"
#include "scene/device.h"

namespace omis {

class EmitterShapes {
public:
    explicit EmitterShapes(std::shared_ptr<Device> device = Device::shared());
    ~EmitterShapes();
    EmitterShapes(const EmitterShapes&) = delete;
    EmitterShapes& operator=(const EmitterShapes&) = delete;

    // Part of light `light`'s shape (a light may add several triangles).
    void add_triangle(std::uint32_t light, const Vec3& a, const Vec3& b, const Vec3& c);
    // Builds the Embree scene; required before lights_along.
    void commit();
    bool empty() const { return light_of_.empty(); }
    // The enlarged triangles (9 floats each) and their lights, until commit():
    // what GeometryScene::set_emitter_candidates takes.
    const std::vector<float>& enlarged_vertices() const { return vertices_; }
    const std::vector<std::uint32_t>& light_of() const { return light_of_; }

    // Appends to `out`, without repeats and in no order, every light whose
    // (enlarged) shape the ray origin + t·direction, t ∈ [0, tmax], crosses —
    // from either side. Thread-safe after commit(). A finite tmax is no
    // exact bound: a light crossed just past it may be listed as well.
    void lights_along(const Vec3& origin, const Vec3& direction,
                      std::vector<std::uint32_t>& out,
                      double tmax = std::numeric_limits<double>::infinity()) const;

private:
    std::shared_ptr<Device> device_;
    RTCScene scene_ = nullptr;
    std::vector<float> vertices_;
    std::vector<std::uint32_t> light_of_;  // per triangle
    bool committed_ = false;
};

}  // namespace omis
