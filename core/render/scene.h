// A scene for direct lighting: triangle meshes in Embree (occluders, and
// emitters when they carry emission) plus lights in physical units.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <vector>

#include "lights/light.h"
#include "render/light_selection.h"
#include "render/receiver.h"
#include "scene/emitter_shapes.h"
#include "scene/geometry_scene.h"

namespace omis {

class Scene {
public:
    Scene() = default;
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    // Returns the mesh id. An emissive mesh also becomes one two-sided
    // triangle light per non-degenerate triangle at commit() — or one mesh
    // light for the whole mesh where it is compact (mesh_lights below).
    std::uint32_t add_mesh(const MeshInput& mesh);
    // Convenience for C++ callers and tests.
    std::uint32_t add_mesh(const std::vector<Vec3>& positions,
                           const std::vector<std::array<std::uint32_t, 3>>& triangles,
                           std::optional<Vec3> emission = std::nullopt);
    // Returns the light id (index into lights()). A second world replaces the first.
    std::uint32_t add_light(const Light& light);
    void set_light_flags(std::uint32_t light, bool cast_shadow, bool visible_to_bsdf);
    // The diffuse closure a mesh's surface has when it is baked (Lambert unless
    // set); before commit.
    void set_mesh_receiver(std::uint32_t mesh, const Receiver& receiver);
    const Receiver& mesh_receiver(std::uint32_t mesh) const;

    // Whether commit() makes a compact emissive mesh one light (LightType::
    // Mesh: directions toward its bounding sphere) instead of a light per
    // triangle: meshes of at least kMeshLightTriangles triangles whose area
    // is at least kMeshLightFill of their bounding sphere's (a sphere-like
    // body fills most of the cone it subtends). On unless set off; before
    // commit. At most kMostMeshLights meshes, the largest (each direction
    // tests every mesh light). Measured on an emissive sphere of 16k triangles (bench/
    // bench_emitters.cpp): relative variance a sample 0.36 -> ~0.01 at a
    // fraction of the time (one closest hit, no light tree).
    void set_mesh_lights(bool on);
    bool mesh_lights_enabled() const { return mesh_lights_; }
    // A mesh's name (errors, snapshots, the command line's --mesh); any time.
    void set_mesh_name(std::uint32_t mesh, const std::string& name);
    static constexpr std::size_t kMeshLightTriangles = 64;
    static constexpr std::size_t kMostMeshLights = 8;
    static constexpr double kMeshLightFill = 0.75;

    // Builds the acceleration structure and the emissive-triangle lights.
    void commit();
    bool committed() const { return committed_; }

    const GeometryScene& geometry() const { return geometry_; }
    // Every light after commit: analytic ones first, then mesh lights, then
    // emissive triangles.
    const std::vector<Light>& lights() const { return lights_; }
    std::size_t num_analytic_lights() const { return analytic_lights_; }
    // The shapes of every area light (rect, ellipse, emissive triangle) in
    // Embree, for finding the lights a direction crosses (after commit).
    const EmitterShapes& emitter_shapes() const { return emitter_shapes_; }
    // The other non-delta lights (sphere lights, sun with an angle, world):
    // few, and looped over per direction.
    const std::vector<std::uint32_t>& unshaped_lights() const { return unshaped_lights_; }
    // Radius of a sphere around the origin holding every mesh and local light.
    double bounding_radius() const { return bounding_radius_; }
    // Per light, Light::power at bounding_radius(), made once at commit: every
    // bake's lighting context and effect plan read it (16k emissive
    // triangles: ~1 ms a bake when each bake made it again). After commit.
    const std::vector<double>& light_powers() const { return light_powers_; }
    // The light selection of `kind` over the non-delta lights (delta = false)
    // or the delta lights (true), in light-id order, as LightSelector builds
    // it with bounding_radius(). Built on first use and kept, so bakes of one
    // scene share one light tree (16k emissive triangles: ~10 ms a build).
    // After commit; any thread.
    const LightSelector& light_selector(LightSelector::Kind kind, bool delta) const;

    // What a pass of a bake of this scene cost, as the bake measured it, by
    // the bake's shape (a key the baker forms from the mesh, the layout, the
    // techniques and the threads): the next time-budgeted bake of the same
    // shape sizes its first pass from it (bake/bake_schedule.cpp). Artists re-bake a scene
    // they change little; the first bake, with nothing measured, spends a
    // one-round pass on measuring. Any thread.
    struct PassCost {
        double first_pass_fixed = 0;  // seconds of the first pass beyond its rounds
        double round = 0;             // seconds of one round over every point
        double rounds = 0;            // how many rounds measured `round`
    };
    std::optional<PassCost> measured_pass_cost(std::uint64_t bake_shape) const;
    void remember_pass_cost(std::uint64_t bake_shape, const PassCost& cost) const;

private:
    void require_uncommitted_light(std::uint32_t light) const;

    void build_emitter_shapes();

    GeometryScene geometry_;
    EmitterShapes emitter_shapes_;
    std::vector<std::uint32_t> unshaped_lights_;
    std::vector<Light> lights_;
    std::vector<double> light_powers_;
    std::vector<Receiver> receivers_;  // per mesh; shorter: Lambert for the rest
    std::size_t analytic_lights_ = 0;
    double bounding_radius_ = 1;
    bool mesh_lights_ = true;
    std::vector<std::uint32_t> light_meshes_;  // the meshes drawn as mesh lights
    bool committed_ = false;
    mutable std::mutex selectors_mutex_;
    mutable std::unique_ptr<LightSelector> selectors_[2][3];  // [delta][kind]
    mutable std::mutex pass_costs_mutex_;
    mutable std::unordered_map<std::uint64_t, PassCost> pass_costs_;
};

}  // namespace omis
