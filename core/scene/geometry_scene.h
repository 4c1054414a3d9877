// Triangle meshes in an Embree scene: what the direct-lighting engine traces
// shadow rays against, and what the baker reads positions/normals/UVs from.
//
// Lifecycle: add meshes, commit(), then query. Queries on a committed scene are
// thread-safe; adding a mesh un-commits the scene (commit again before querying,
// and never while other threads query).
#pragma once

#include <embree3/rtcore.h>

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "math/vec3.h"
#include "scene/device.h"

namespace omis {

// Read-only view of a C-contiguous (rows, cols) array of float or double,
// as it arrives from numpy or the C ABI. The caller keeps ownership; add_mesh
// copies what it needs before returning.
struct ScalarArray {
    const float* f32 = nullptr;   // exactly one of f32/f64 set, or neither (absent)
    const double* f64 = nullptr;
    std::size_t rows = 0, cols = 0;

    static ScalarArray of(const float* data, std::size_t rows, std::size_t cols) {
        ScalarArray a; a.f32 = data; a.rows = rows; a.cols = cols; return a;
    }
    static ScalarArray of(const double* data, std::size_t rows, std::size_t cols) {
        ScalarArray a; a.f64 = data; a.rows = rows; a.cols = cols; return a;
    }
    bool present() const { return f32 || f64; }
    double at(std::size_t r, std::size_t c) const {
        return f32 ? double(f32[r * cols + c]) : f64[r * cols + c];
    }
};

// Read-only view of a C-contiguous (rows, cols) uint32 array.
struct IndexArray {
    const std::uint32_t* data = nullptr;
    std::size_t rows = 0, cols = 0;
};

struct MeshInput {
    std::string name;        // used in error messages only
    ScalarArray positions;   // (V, 3) world space, metres
    IndexArray triangles;    // (T, 3) vertex indices, counter-clockwise = front
    ScalarArray normals;     // optional (3T, 3) per-corner shading normals
    ScalarArray uvs;         // optional (3T, 2) per-corner texture coordinates
    // Optional emitted radiance, W/(m² sr) per RGB channel; absent or all zero
    // means not emissive.
    std::optional<Vec3> emission;
};

// A mesh after validation, in double precision.
struct Mesh {
    std::string name;
    std::vector<Vec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::vector<Vec3> corner_normals;                 // empty: flat shading
    std::vector<std::array<double, 2>> corner_uvs;    // empty: no UVs
    std::optional<Vec3> emission;                     // radiance W/(m² sr), RGB
    double area = 0;                                  // total, m²
    std::size_t degenerate_triangles = 0;             // zero-area, kept but never hit

    bool has_normals() const { return !corner_normals.empty(); }
    bool has_uvs() const { return !corner_uvs.empty(); }
    bool is_emissive() const { return emission.has_value(); }
    std::size_t num_triangles() const { return triangles.size(); }

    std::array<Vec3, 3> triangle_vertices(std::uint32_t tri) const;
    double triangle_area(std::uint32_t tri) const;
    // Unit normal of the triangle's plane, oriented by the winding
    // (v1-v0)x(v2-v0); zero vector for a degenerate triangle.
    Vec3 geometric_normal(std::uint32_t tri) const;
    // Interpolated per-corner normal (normalised) at barycentrics (b1, b2) of
    // vertices 1 and 2; the geometric normal when the mesh has no normals.
    Vec3 shading_normal(std::uint32_t tri, double b1, double b2) const;
    Vec3 position(std::uint32_t tri, double b1, double b2) const;
};

// One emissive triangle, ready to become an area light.
struct EmissiveTriangle {
    std::array<Vec3, 3> vertices;  // world space, in the mesh's winding order
    Vec3 radiance;                 // W/(m² sr), RGB
    Vec3 normal;                   // unit, from the winding
    double area = 0;               // m²
    std::uint32_t mesh = 0, triangle = 0;
};

// What a closest-hit query finds, without reading the mesh (a shadow test
// needs no more; Hit adds the surface, a cache miss among many triangles).
struct RayHit {
    double t = 0;                  // distance along the ray, in units of |direction|
    std::uint32_t mesh = 0;        // id returned by add_mesh
    std::uint32_t triangle = 0;    // index into the mesh's triangles
    double b1 = 0, b2 = 0;         // barycentrics of vertices 1 and 2 (Embree's u, v)
};

struct Hit {
    double t = 0;                  // distance along the ray, in units of |direction|
    std::uint32_t mesh = 0;        // id returned by add_mesh
    std::uint32_t triangle = 0;    // index into the mesh's triangles
    double b1 = 0, b2 = 0;         // barycentrics of vertices 1 and 2 (Embree's u, v)
    Vec3 geometric_normal;         // unit, winding-oriented (not flipped to the ray)
    Vec3 position;                 // from the barycentrics, double precision
};

// A ray for the batch query.
struct Ray {
    Vec3 origin, direction;
    double tmin = 0, tmax = 0;
};

struct SceneOptions {
    // Embree's HIGH quality builder (spatial splits) pays at build time for
    // faster traversal; bakes trace millions of rays per build.
    RTCBuildQuality build_quality = RTC_BUILD_QUALITY_HIGH;
};

class GeometryScene {
public:
    explicit GeometryScene(std::shared_ptr<Device> device = Device::shared(),
                           SceneOptions options = {});
    ~GeometryScene();
    GeometryScene(const GeometryScene&) = delete;
    GeometryScene& operator=(const GeometryScene&) = delete;

    // Validates and copies a mesh; returns its id (0, 1, ...). Throws
    // std::invalid_argument naming the mesh and the problem. Degenerate
    // triangles are allowed and counted in Mesh::degenerate_triangles.
    std::uint32_t add_mesh(const MeshInput& input);
    // Convenience for C++ callers and tests.
    std::uint32_t add_mesh(const std::vector<Vec3>& positions,
                           const std::vector<std::array<std::uint32_t, 3>>& triangles,
                           std::optional<Vec3> emission = std::nullopt,
                           const std::string& name = "");

    // Builds the acceleration structure (robust mode). Required before queries.
    void commit();
    bool committed() const { return committed_; }

    // True when some mesh has a non-degenerate triangle. Without occluders the
    // queries answer at once and trace no rays.
    bool has_occluders() const { return occluder_triangles_ > 0; }

    // Is anything hit with t in [tmin, tmax]? direction need not be unit; t is in
    // its units. Thread-safe after commit().
    bool occluded(const Vec3& origin, const Vec3& direction, double tmin,
                  double tmax) const;
    // The closest hit with t in [tmin, tmax], if any. Thread-safe after commit().
    std::optional<Hit> intersect(const Vec3& origin, const Vec3& direction,
                                 double tmin, double tmax) const;
    // The same hit without its surface (normal, position).
    std::optional<RayHit> closest_hit(const Vec3& origin, const Vec3& direction,
                                      double tmin, double tmax) const;
    // occluded() for many rays at once (Embree's stream API); out[i] = occluded.
    void occluded(const Ray* rays, std::size_t count, bool* out) const;

    // Emitter candidates (EmitterShapes' enlarged shapes: 9 floats and a
    // light id per triangle) traced beside the meshes by
    // closest_hit_and_emitters, so that a light sample's closest hit and the
    // lights along its ray take one traversal. The other queries never see
    // them. The lights of emissive meshes' triangles need no candidate (one
    // would double the triangles the traversal meets): `mesh_lights` names
    // them, and their triangles' own hits list them. Set before commit();
    // add_mesh drops them.
    struct MeshTriangleLight {
        std::uint32_t mesh = 0, triangle = 0, light = 0;
    };
    // `opaque_meshes`: emissive meshes drawn as one light each (mesh lights):
    // their triangles list no light, and a hit on one stops the traversal
    // as a mesh that does not emit would.
    void set_emitter_candidates(const std::vector<float>& vertices,
                                std::vector<std::uint32_t> light_of,
                                const std::vector<MeshTriangleLight>& mesh_lights = {},
                                const std::vector<std::uint32_t>& opaque_meshes = {});
    bool has_emitter_candidates() const { return emitter_query_; }
    // closest_hit(origin, direction, 0, ∞), and appended to `lights` (with
    // repeats, in no order) every emitter candidate the ray crosses up to
    // that hit and the lights of the emissive triangles it hits — all along
    // it where the hit is on an emissive mesh or there is none, and no
    // emissive triangle was hit near its edge: `complete` then says so (the
    // traversal goes on past emissive meshes, which are lights too), and
    // every light whose exact shape the ray crosses is listed (where
    // single precision misses a triangle crossed near its edge, a
    // neighbour's hit there leaves the list incomplete). Requires
    // has_emitter_candidates().
    // `on_listed` (if set) is told of each light as it is appended, while
    // the traversal goes on: the caller may start reading what it will need
    // of the light (among 100k lights, a cache miss each) meanwhile.
    using ListedLight = void (*)(void* context, std::uint32_t light);
    std::optional<RayHit> closest_hit_and_emitters(const Vec3& origin, const Vec3& direction,
                                                   std::vector<std::uint32_t>& lights,
                                                   bool& complete,
                                                   ListedLight on_listed = nullptr,
                                                   void* on_listed_context = nullptr) const;
    // An emissive mesh's lights (set_emitter_candidates): triangle t's is
    // first + t where `consecutive`, else the table's entry first + t (~0u:
    // none).
    struct MeshLights {
        std::uint32_t first = 0;
        bool consecutive = false;
        bool opaque = false;  // a mesh light's mesh (set_emitter_candidates)
    };

    // Rays handed to Embree since construction or the last reset, summed over
    // per-thread counters.
    std::uint64_t rays_traced() const;
    void reset_ray_count();

    std::size_t num_meshes() const { return meshes_.size(); }
    const Mesh& mesh(std::uint32_t id) const;
    const std::vector<Mesh>& meshes() const { return meshes_; }
    // Names a mesh (names appear in errors and let callers find meshes).
    void set_mesh_name(std::uint32_t id, const std::string& name);
    // Every non-degenerate triangle of every emissive mesh.
    std::vector<EmissiveTriangle> emissive_triangles() const;

    RTCScene handle() const { return scene_; }

private:
    // Hands Embree its single-precision copy of a validated mesh, as geometry `id`.
    void attach_to_embree(const Mesh& mesh, std::uint32_t id, const std::string& who);
    void require_committed(const char* what) const;
    // closest_hit, and Embree's (unnormalised) geometric normal of the hit.
    std::optional<RayHit> closest_hit(const Vec3& origin, const Vec3& direction, double tmin,
                                      double tmax, Vec3* embree_normal) const;
    void count_rays(std::uint64_t n) const;

    std::shared_ptr<Device> device_;
    SceneOptions options_;
    RTCScene scene_ = nullptr;
    std::vector<Mesh> meshes_;
    std::size_t occluder_triangles_ = 0;
    // The emitter candidates' Embree geometry id (~0u: none) and light ids.
    std::uint32_t candidates_geometry_ = ~0u;
    std::vector<std::uint32_t> candidate_light_of_;
    // Per mesh, its emissive triangles' lights; the table of those that are
    // not consecutive (~0u: none).
    std::vector<MeshLights> mesh_lights_;
    std::vector<std::uint32_t> mesh_light_;
    bool emitter_query_ = false;  // set_emitter_candidates was called
    void drop_emitter_candidates();  // detaches them, if any
    bool committed_ = false;

    // Per-thread ray counters: each thread adds to its own cache line.
    static constexpr std::size_t kCounterSlots = 64;
    struct alignas(64) Counter {
        std::atomic<std::uint64_t> n{0};
    };
    std::unique_ptr<Counter[]> counters_;
};

}  // namespace omis
