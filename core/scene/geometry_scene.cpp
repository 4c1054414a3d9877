#include "scene/geometry_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "scene/ray_offset.h"

namespace omis {

namespace {

std::string fmt(const Vec3& v) {
    std::ostringstream s;
    s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
    return s.str();
}

std::string shape(std::size_t rows, std::size_t cols) {
    return "(" + std::to_string(rows) + ", " + std::to_string(cols) + ")";
}

// Nearest float not above / not below x, so a float ray interval never extends
// past the double interval the caller asked for.
float float_down(double x) {
    float f = static_cast<float>(x);
    if (static_cast<double>(f) > x) f = std::nextafter(f, -INFINITY);
    return f;
}
float float_up(double x) {
    float f = static_cast<float>(x);
    if (static_cast<double>(f) < x) f = std::nextafter(f, INFINITY);
    return f;
}

// Embree geometry masks: meshes, and the emitter candidates that only
// closest_hit_and_emitters traces.
constexpr unsigned kMeshMask = 1, kCandidateMask = 2;

// How near an edge (in barycentrics) an emissive triangle's hit makes
// closest_hit_and_emitters' list incomplete. A ray that single precision
// lets miss a triangle it crosses in exact arithmetic passes within float
// rounding (~1e-7 of the coordinates) of that triangle's edge, and so of
// its neighbour's, which it hits there. 1e-3 is the margin of the emitter
// shapes' enlargement (EmitterShapes: 1e-3 about the centroid moves an edge
// by 1e-3 of the centroid's distance to it, a third of the height) times
// three: such a ray is left to EmitterShapes::lights_along.
constexpr float kNearEdge = 1e-3f;

// An intersection context that closest_hit_and_emitters extends: the filter of
// emissive meshes and candidates acts only where `emitters` is set.
struct EmitterQuery {
    const std::uint32_t* light_of = nullptr;
    std::uint32_t candidates = ~0u;  // their geometry id
    // Emissive meshes' lights (GeometryScene::MeshLights, per mesh), and the
    // table of those whose triangles' lights are not consecutive.
    const GeometryScene::MeshLights* mesh_lights = nullptr;
    const std::uint32_t* mesh_light = nullptr;
    std::vector<std::uint32_t>* lights = nullptr;
    // Told of each light as it is listed (may be null).
    GeometryScene::ListedLight on_listed = nullptr;
    void* on_listed_context = nullptr;
    void list(std::uint32_t light) {
        lights->push_back(light);
        if (on_listed) on_listed(on_listed_context, light);
    }
    // The closest hit on an emissive mesh so far (rejected, so that the
    // traversal goes on to the lights behind it).
    float t = INFINITY, u = 0, v = 0;
    std::uint32_t mesh = ~0u, triangle = 0;
    // Some emissive triangle was hit near its edge: a neighbour's light
    // may be crossed where single precision says it is not.
    bool near_edge = false;
};
struct QueryContext {
    RTCIntersectContext context;  // first: Embree hands filters this pointer
    EmitterQuery* emitters = nullptr;
};

// Intersect filter of emissive meshes and of the candidates: a candidate is
// listed and passed over; an emissive mesh's hit is kept aside as the
// closest so far and passed over too. Other queries accept every hit.
void emitter_filter(const RTCFilterFunctionNArguments* args) {
    EmitterQuery* q = reinterpret_cast<const QueryContext*>(args->context)->emitters;
    if (!q) return;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const unsigned geometry = RTCHitN_geomID(args->hit, args->N, i);
        // A mesh light's mesh: its hit is kept, as a mesh that does not emit.
        if (geometry != q->candidates && q->mesh_lights[geometry].opaque) continue;
        args->valid[i] = 0;
        const unsigned primitive = RTCHitN_primID(args->hit, args->N, i);
        if (geometry == q->candidates) {
            q->list(q->light_of[primitive]);
            continue;
        }
        // An emissive mesh's triangle: its light is listed (it has no
        // candidate: the hit is the triangle's own).
        const float t = RTCRayN_tfar(args->ray, args->N, i);
        const float u = RTCHitN_u(args->hit, args->N, i), v = RTCHitN_v(args->hit, args->N, i);
        const GeometryScene::MeshLights& m = q->mesh_lights[geometry];
        const std::uint32_t light =
            m.consecutive ? m.first + primitive : q->mesh_light[m.first + primitive];
        if (light != ~0u) q->list(light);
        q->near_edge = q->near_edge || std::min({u, v, 1.0f - u - v}) < kNearEdge;
        if (t < q->t) {
            q->t = t;
            q->u = u;
            q->v = v;
            q->mesh = geometry;
            q->triangle = primitive;
        }
    }
}

// The hit Embree kept.
RayHit hit_of(const RTCRayHit& rh) {
    RayHit hit;
    hit.t = rh.ray.tfar;
    hit.mesh = rh.hit.geomID;
    hit.triangle = rh.hit.primID;
    hit.b1 = rh.hit.u;
    hit.b2 = rh.hit.v;
    return hit;
}

// Fills an Embree ray; false when the interval is empty (nothing to trace).
bool make_ray(const Vec3& o, const Vec3& d, double tmin, double tmax, RTCRay& ray) {
    const double lo = tmin > 0.0 ? tmin : 0.0;  // Embree needs tnear >= 0
    if (!(tmax >= lo)) return false;             // also rejects NaN
    ray.org_x = float(o.x); ray.org_y = float(o.y); ray.org_z = float(o.z);
    ray.dir_x = float(d.x); ray.dir_y = float(d.y); ray.dir_z = float(d.z);
    ray.tnear = float_up(lo);
    ray.tfar = float_down(tmax);
    ray.time = 0.0f;
    ray.mask = kMeshMask;
    ray.id = 0;
    ray.flags = 0;
    return ray.tfar >= ray.tnear;
}

// Throws std::invalid_argument naming the mesh (`who`) and the problem.
struct MeshError {
    std::string who;
    [[noreturn]] void operator()(const std::string& what) const {
        throw std::invalid_argument(who + what);
    }
};

// The input arrays' presence and shapes, and the emission's range.
void check_shapes(const MeshInput& in, const MeshError& fail) {
    if (!in.positions.present()) fail("positions are missing");
    if (!in.triangles.data && in.triangles.rows > 0) fail("triangles are missing");
    if (in.positions.cols != 3)
        fail("positions must have shape (V, 3), got " + shape(in.positions.rows, in.positions.cols));
    if (in.triangles.cols != 3)
        fail("triangles must have shape (T, 3), got " + shape(in.triangles.rows, in.triangles.cols));
    if (in.positions.rows == 0) fail("empty mesh: no vertices");
    if (in.triangles.rows == 0) fail("empty mesh: no triangles");
    const std::size_t V = in.positions.rows, T = in.triangles.rows;
    if (T > (std::size_t(1) << 31) || V > (std::size_t(1) << 32) - 1)
        fail("too many vertices or triangles for Embree");
    if (in.normals.present() && (in.normals.rows != 3 * T || in.normals.cols != 3))
        fail("normals must be per corner with shape (3T, 3) = " + shape(3 * T, 3) + ", got " +
             shape(in.normals.rows, in.normals.cols));
    if (in.uvs.present() && (in.uvs.rows != 3 * T || in.uvs.cols != 2))
        fail("uvs must be per corner with shape (3T, 2) = " + shape(3 * T, 2) + ", got " +
             shape(in.uvs.rows, in.uvs.cols));
    if (in.emission && (!isfinite(*in.emission) || in.emission->x < 0 ||
                        in.emission->y < 0 || in.emission->z < 0))
        fail("emission must be finite and non-negative, got " + fmt(*in.emission));
}

std::vector<Vec3> copy_positions(const ScalarArray& positions, const MeshError& fail) {
    std::vector<Vec3> out(positions.rows);
    for (std::size_t i = 0; i < out.size(); ++i) {
        const Vec3 p{positions.at(i, 0), positions.at(i, 1), positions.at(i, 2)};
        if (!isfinite(p)) fail("vertex " + std::to_string(i) + " is not finite: " + fmt(p));
        // Embree stores floats and refuses rays beyond its FLT_LARGE (1.8e18).
        if (!traceable(p))
            fail("vertex " + std::to_string(i) + " lies beyond ±1e18 m, the range rays reach: " +
                 fmt(p));
        out[i] = p;
    }
    return out;
}

std::vector<std::array<std::uint32_t, 3>> copy_triangles(const IndexArray& triangles,
                                                         std::size_t num_vertices,
                                                         const MeshError& fail) {
    std::vector<std::array<std::uint32_t, 3>> out(triangles.rows);
    for (std::size_t t = 0; t < out.size(); ++t) {
        const std::uint32_t* idx = triangles.data + 3 * t;
        for (int k = 0; k < 3; ++k) {
            if (idx[k] >= num_vertices) {
                fail("triangle " + std::to_string(t) + " = (" + std::to_string(idx[0]) + ", " +
                     std::to_string(idx[1]) + ", " + std::to_string(idx[2]) +
                     ") has vertex index " + std::to_string(idx[k]) +
                     " out of range (mesh has " + std::to_string(num_vertices) + " vertices)");
            }
        }
        out[t] = {idx[0], idx[1], idx[2]};
    }
    return out;
}

std::vector<Vec3> copy_corner_normals(const ScalarArray& normals, const MeshError& fail) {
    std::vector<Vec3> out(normals.rows);
    for (std::size_t c = 0; c < out.size(); ++c) {
        const Vec3 n{normals.at(c, 0), normals.at(c, 1), normals.at(c, 2)};
        if (!isfinite(n))
            fail("normal of corner " + std::to_string(c) + " (triangle " +
                 std::to_string(c / 3) + ") is not finite: " + fmt(n));
        out[c] = n;
    }
    return out;
}

std::vector<std::array<double, 2>> copy_corner_uvs(const ScalarArray& uvs,
                                                   const MeshError& fail) {
    std::vector<std::array<double, 2>> out(uvs.rows);
    for (std::size_t c = 0; c < out.size(); ++c) {
        const double u = uvs.at(c, 0), v = uvs.at(c, 1);
        if (!std::isfinite(u) || !std::isfinite(v))
            fail("uv of corner " + std::to_string(c) + " (triangle " + std::to_string(c / 3) +
                 ") is not finite");
        out[c] = {u, v};
    }
    return out;
}

// Twice the triangle's area, or 0 when it is degenerate: zero area, or an angle
// too thin to have a meaningful plane. Degenerate triangles stay in the mesh
// (indices are stable for baking) but are never hit and never become lights.
double proper_twice_area(const std::array<Vec3, 3>& v, Vec3* plane_normal = nullptr) {
    const Vec3 e1 = v[1] - v[0], e2 = v[2] - v[0];
    const Vec3 c = cross(e1, e2);
    const double twice_area = length(c);
    if (!(twice_area > 1e-12 * length(e1) * length(e2))) return 0.0;
    if (plane_normal) *plane_normal = c / twice_area;
    return twice_area;
}

// Sets the mesh's area and degenerate-triangle count; returns the number of
// proper (traceable) triangles.
std::size_t measure_triangles(Mesh& m) {
    std::size_t good = 0;
    for (std::uint32_t t = 0; t < m.num_triangles(); ++t) {
        const double twice_area = proper_twice_area(m.triangle_vertices(t));
        if (twice_area == 0.0) {
            ++m.degenerate_triangles;
        } else {
            m.area += 0.5 * twice_area;
            ++good;
        }
    }
    return good;
}

std::size_t thread_slot(std::size_t slots) {
    static std::atomic<std::size_t> next{0};
    thread_local const std::size_t slot = next.fetch_add(1, std::memory_order_relaxed);
    return slot % slots;
}

}  // namespace

// ---------------------------------------------------------------------------
// Mesh

std::array<Vec3, 3> Mesh::triangle_vertices(std::uint32_t tri) const {
    const auto& t = triangles.at(tri);
    return {positions[t[0]], positions[t[1]], positions[t[2]]};
}

double Mesh::triangle_area(std::uint32_t tri) const {
    const auto v = triangle_vertices(tri);
    return 0.5 * length(cross(v[1] - v[0], v[2] - v[0]));
}

Vec3 Mesh::geometric_normal(std::uint32_t tri) const {
    const auto v = triangle_vertices(tri);
    const Vec3 n = cross(v[1] - v[0], v[2] - v[0]);
    const double len = length(n);
    return len > 0.0 ? n / len : Vec3{};
}

Vec3 Mesh::shading_normal(std::uint32_t tri, double b1, double b2) const {
    if (has_normals()) {
        const std::size_t c = 3 * std::size_t(tri);
        const Vec3 n = (1.0 - b1 - b2) * corner_normals.at(c) + b1 * corner_normals[c + 1] +
                       b2 * corner_normals[c + 2];
        const double len = length(n);
        if (len > 0.0 && std::isfinite(len)) return n / len;
    }
    return geometric_normal(tri);
}

Vec3 Mesh::position(std::uint32_t tri, double b1, double b2) const {
    const auto v = triangle_vertices(tri);
    return (1.0 - b1 - b2) * v[0] + b1 * v[1] + b2 * v[2];
}

// ---------------------------------------------------------------------------
// GeometryScene

GeometryScene::GeometryScene(std::shared_ptr<Device> device, SceneOptions options)
    : device_(std::move(device)), options_(options), counters_(new Counter[kCounterSlots]) {
    if (!device_) throw std::invalid_argument("GeometryScene: device is null");
    scene_ = rtcNewScene(device_->handle());
    device_->check();
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, options_.build_quality);
    device_->check();
}

GeometryScene::~GeometryScene() {
    if (scene_) rtcReleaseScene(scene_);
}

std::uint32_t GeometryScene::add_mesh(const MeshInput& in) {
    const auto id = static_cast<std::uint32_t>(meshes_.size());
    const MeshError fail{"add_mesh: mesh " + std::to_string(id) +
                         (in.name.empty() ? "" : " '" + in.name + "'") + ": "};
    check_shapes(in, fail);

    Mesh m;
    m.name = in.name;
    m.positions = copy_positions(in.positions, fail);
    m.triangles = copy_triangles(in.triangles, in.positions.rows, fail);
    if (in.normals.present()) m.corner_normals = copy_corner_normals(in.normals, fail);
    if (in.uvs.present()) m.corner_uvs = copy_corner_uvs(in.uvs, fail);
    if (in.emission && (in.emission->x > 0 || in.emission->y > 0 || in.emission->z > 0))
        m.emission = in.emission;
    const std::size_t good = measure_triangles(m);

    drop_emitter_candidates();  // their id is the next mesh's
    attach_to_embree(m, id, fail.who);
    meshes_.push_back(std::move(m));
    occluder_triangles_ += good;
    committed_ = false;
    return id;
}

void GeometryScene::attach_to_embree(const Mesh& m, std::uint32_t id,
                                     const std::string& who) {
    // Embree keeps its own single-precision copy.
    const std::size_t V = m.positions.size(), T = m.triangles.size();
    RTCGeometry geom = rtcNewGeometry(device_->handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
    device_->check();
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), V));
    auto* ib = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), T));
    if (!vb || !ib) {
        rtcReleaseGeometry(geom);
        device_->check();
        throw std::runtime_error(who + "Embree could not allocate buffers");
    }
    for (std::size_t i = 0; i < V; ++i) {
        vb[3 * i + 0] = float(m.positions[i].x);
        vb[3 * i + 1] = float(m.positions[i].y);
        vb[3 * i + 2] = float(m.positions[i].z);
    }
    for (std::size_t t = 0; t < T; ++t)
        for (int k = 0; k < 3; ++k) ib[3 * t + k] = m.triangles[t][k];
    rtcSetGeometryBuildQuality(geom, options_.build_quality);
    rtcSetGeometryMask(geom, kMeshMask);
    if (m.is_emissive()) rtcSetGeometryIntersectFilterFunction(geom, emitter_filter);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene_, geom, id);
    rtcReleaseGeometry(geom);
    device_->check();
}

std::uint32_t GeometryScene::add_mesh(const std::vector<Vec3>& positions,
                                      const std::vector<std::array<std::uint32_t, 3>>& triangles,
                                      std::optional<Vec3> emission, const std::string& name) {
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
    static_assert(sizeof(std::array<std::uint32_t, 3>) == 3 * sizeof(std::uint32_t), "");
    MeshInput in;
    in.name = name;
    in.positions = ScalarArray::of(positions.empty() ? nullptr : &positions[0].x,
                                   positions.size(), 3);
    if (positions.empty()) {  // still report "empty", not "missing"
        static const double none = 0;
        in.positions = ScalarArray::of(&none, 0, 3);
    }
    in.triangles.data = triangles.empty() ? nullptr : triangles[0].data();
    in.triangles.rows = triangles.size();
    in.triangles.cols = 3;
    in.emission = emission;
    return add_mesh(in);
}

void GeometryScene::set_mesh_name(std::uint32_t id, const std::string& name) {
    if (id >= meshes_.size())
        throw std::invalid_argument("mesh: id " + std::to_string(id) + " is out of range (" +
                                    std::to_string(meshes_.size()) + " meshes)");
    meshes_[id].name = name;
}

void GeometryScene::commit() {
    rtcCommitScene(scene_);
    device_->check();
    committed_ = true;
}

void GeometryScene::require_committed(const char* what) const {
    if (!committed_)
        throw std::logic_error(std::string("GeometryScene::") + what +
                               ": scene is not committed (call commit() after adding meshes)");
}

void GeometryScene::count_rays(std::uint64_t n) const {
    counters_[thread_slot(kCounterSlots)].n.fetch_add(n, std::memory_order_relaxed);
}

std::uint64_t GeometryScene::rays_traced() const {
    std::uint64_t sum = 0;
    for (std::size_t i = 0; i < kCounterSlots; ++i)
        sum += counters_[i].n.load(std::memory_order_relaxed);
    return sum;
}

void GeometryScene::reset_ray_count() {
    for (std::size_t i = 0; i < kCounterSlots; ++i)
        counters_[i].n.store(0, std::memory_order_relaxed);
}

bool GeometryScene::occluded(const Vec3& origin, const Vec3& direction, double tmin,
                             double tmax) const {
    require_committed("occluded");
    if (!has_occluders()) return false;
    RTCRay ray;
    if (!make_ray(origin, direction, tmin, tmax, ray)) return false;
    QueryContext ctx;
    rtcInitIntersectContext(&ctx.context);
    rtcOccluded1(scene_, &ctx.context, &ray);
    count_rays(1);
    return ray.tfar < 0.0f;  // Embree sets tfar = -inf on a hit
}

std::optional<RayHit> GeometryScene::closest_hit(const Vec3& origin, const Vec3& direction,
                                                 double tmin, double tmax) const {
    return closest_hit(origin, direction, tmin, tmax, nullptr);
}

std::optional<RayHit> GeometryScene::closest_hit(const Vec3& origin, const Vec3& direction,
                                                 double tmin, double tmax,
                                                 Vec3* embree_normal) const {
    require_committed("intersect");
    if (!has_occluders()) return std::nullopt;
    RTCRayHit rh;
    if (!make_ray(origin, direction, tmin, tmax, rh.ray)) return std::nullopt;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    QueryContext ctx;  // the emissive meshes' filter reads it
    rtcInitIntersectContext(&ctx.context);
    rtcIntersect1(scene_, &ctx.context, &rh);
    count_rays(1);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    if (embree_normal) *embree_normal = Vec3{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    return hit_of(rh);
}

std::optional<Hit> GeometryScene::intersect(const Vec3& origin, const Vec3& direction,
                                            double tmin, double tmax) const {
    Vec3 embree_normal;
    const auto h = closest_hit(origin, direction, tmin, tmax, &embree_normal);
    if (!h) return std::nullopt;
    const Mesh& m = meshes_[h->mesh];
    Hit hit;
    hit.t = h->t;
    hit.mesh = h->mesh;
    hit.triangle = h->triangle;
    hit.b1 = h->b1;
    hit.b2 = h->b2;
    hit.geometric_normal = m.geometric_normal(hit.triangle);
    if (length(hit.geometric_normal) == 0.0)  // degenerate in double, not in float
        hit.geometric_normal = normalize(embree_normal);
    hit.position = m.position(hit.triangle, hit.b1, hit.b2);
    return hit;
}

void GeometryScene::occluded(const Ray* rays, std::size_t count, bool* out) const {
    require_committed("occluded");
    if (!has_occluders()) {
        for (std::size_t i = 0; i < count; ++i) out[i] = false;
        return;
    }
    constexpr std::size_t kChunk = 256;
    RTCRay buf[kChunk];
    std::size_t where[kChunk];
    QueryContext ctx;
    rtcInitIntersectContext(&ctx.context);
    for (std::size_t start = 0; start < count; start += kChunk) {
        const std::size_t end = std::min(count, start + kChunk);
        unsigned n = 0;
        for (std::size_t i = start; i < end; ++i) {
            out[i] = false;
            const Ray& r = rays[i];
            if (make_ray(r.origin, r.direction, r.tmin, r.tmax, buf[n])) where[n++] = i;
        }
        if (n == 0) continue;
        rtcOccluded1M(scene_, &ctx.context, buf, n, sizeof(RTCRay));
        count_rays(n);
        for (unsigned k = 0; k < n; ++k) out[where[k]] = buf[k].tfar < 0.0f;
    }
}

void GeometryScene::drop_emitter_candidates() {
    emitter_query_ = false;
    mesh_light_.clear();
    mesh_lights_.clear();
    if (candidates_geometry_ == ~0u) return;
    rtcDetachGeometry(scene_, candidates_geometry_);
    candidates_geometry_ = ~0u;
    candidate_light_of_.clear();
}

void GeometryScene::set_emitter_candidates(const std::vector<float>& vertices,
                                           std::vector<std::uint32_t> light_of,
                                           const std::vector<MeshTriangleLight>& mesh_lights,
                                           const std::vector<std::uint32_t>& opaque_meshes) {
    drop_emitter_candidates();
    committed_ = false;
    // Every emissive mesh's triangles, ~0u where a triangle has no light.
    std::vector<std::uint32_t> start(meshes_.size(), 0);
    std::size_t emissive_triangles = 0;
    for (std::size_t m = 0; m < meshes_.size(); ++m) {
        start[m] = std::uint32_t(emissive_triangles);
        if (meshes_[m].is_emissive()) emissive_triangles += meshes_[m].num_triangles();
    }
    std::vector<std::uint32_t> all(emissive_triangles, ~0u);
    for (const MeshTriangleLight& l : mesh_lights) {
        if (l.mesh >= meshes_.size() || !meshes_[l.mesh].is_emissive() ||
            l.triangle >= meshes_[l.mesh].num_triangles())
            throw std::invalid_argument("set_emitter_candidates: no emissive triangle " +
                                        std::to_string(l.triangle) + " in mesh " +
                                        std::to_string(l.mesh));
        all[start[l.mesh] + l.triangle] = l.light;
    }
    // A mesh whose triangles are lights first, first + 1, ... (one light per
    // triangle, in order: no degenerate triangle) needs no table, and the
    // traversal no read of it (among 100k triangles, a cache miss a hit).
    mesh_lights_.assign(meshes_.size(), MeshLights{});
    for (std::size_t m = 0; m < meshes_.size(); ++m) {
        if (!meshes_[m].is_emissive()) continue;
        const std::uint32_t* own = all.data() + start[m];
        const std::size_t n = meshes_[m].num_triangles();
        bool consecutive = own[0] != ~0u;
        for (std::size_t t = 1; t < n && consecutive; ++t) consecutive = own[t] == own[0] + t;
        if (consecutive) {
            mesh_lights_[m] = {own[0], true};
        } else {
            mesh_lights_[m] = {std::uint32_t(mesh_light_.size()), false};
            mesh_light_.insert(mesh_light_.end(), own, own + n);
        }
    }
    for (std::uint32_t m : opaque_meshes) {
        if (m >= meshes_.size() || !meshes_[m].is_emissive())
            throw std::invalid_argument("set_emitter_candidates: mesh " + std::to_string(m) +
                                        " is not an emissive mesh");
        mesh_lights_[m].opaque = true;
    }
    emitter_query_ = true;
    const std::size_t triangles = light_of.size();
    if (triangles == 0 || vertices.size() != 9 * triangles) return;
    RTCGeometry geom = new_triangle_soup(*device_, vertices, "emitter candidates");
    rtcSetGeometryBuildQuality(geom, options_.build_quality);
    rtcSetGeometryMask(geom, kCandidateMask);
    rtcSetGeometryIntersectFilterFunction(geom, emitter_filter);
    rtcCommitGeometry(geom);
    const auto id = std::uint32_t(meshes_.size());
    rtcAttachGeometryByID(scene_, geom, id);
    rtcReleaseGeometry(geom);
    device_->check();
    candidates_geometry_ = id;
    candidate_light_of_ = std::move(light_of);
}

std::optional<RayHit> GeometryScene::closest_hit_and_emitters(
    const Vec3& origin, const Vec3& direction, std::vector<std::uint32_t>& lights,
    bool& complete, ListedLight on_listed, void* on_listed_context) const {
    require_committed("closest_hit_and_emitters");
    if (!has_emitter_candidates())
        throw std::logic_error("GeometryScene::closest_hit_and_emitters: no emitter candidates");
    complete = true;
    if (!has_occluders() && candidates_geometry_ == ~0u) return std::nullopt;
    complete = true;
    RTCRayHit rh;
    if (!make_ray(origin, direction, 0, std::numeric_limits<double>::infinity(), rh.ray))
        return std::nullopt;
    rh.ray.mask = kMeshMask | kCandidateMask;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    EmitterQuery q;
    q.light_of = candidate_light_of_.data();
    q.candidates = candidates_geometry_;
    q.mesh_lights = mesh_lights_.data();
    q.mesh_light = mesh_light_.data();
    q.lights = &lights;
    q.on_listed = on_listed;
    q.on_listed_context = on_listed_context;
    QueryContext ctx;
    rtcInitIntersectContext(&ctx.context);
    ctx.emitters = &q;
    rtcIntersect1(scene_, &ctx.context, &rh);
    count_rays(1);
    // A hit Embree kept is on a mesh that does not emit, or on a mesh
    // light's: nothing past it was looked for.
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
        complete = false;
        if (!(q.t < rh.ray.tfar)) return hit_of(rh);
    }
    complete = complete && !q.near_edge;
    if (q.mesh == ~0u) return std::nullopt;
    RayHit hit;  // the closest emissive hit, set aside by the filter
    hit.t = q.t;
    hit.mesh = q.mesh;
    hit.triangle = q.triangle;
    hit.b1 = q.u;
    hit.b2 = q.v;
    return hit;
}

const Mesh& GeometryScene::mesh(std::uint32_t id) const {
    if (id >= meshes_.size())
        throw std::out_of_range("GeometryScene::mesh: no mesh " + std::to_string(id) + " (have " +
                                std::to_string(meshes_.size()) + ")");
    return meshes_[id];
}

std::vector<EmissiveTriangle> GeometryScene::emissive_triangles() const {
    std::vector<EmissiveTriangle> out;
    std::size_t most = 0;  // degenerate ones included
    for (const Mesh& m : meshes_)
        if (m.is_emissive()) most += m.num_triangles();
    out.reserve(most);
    for (std::uint32_t id = 0; id < meshes_.size(); ++id) {
        const Mesh& m = meshes_[id];
        if (!m.is_emissive()) continue;
        for (std::uint32_t t = 0; t < m.num_triangles(); ++t) {
            const auto v = m.triangle_vertices(t);
            EmissiveTriangle e;
            const double twice_area = proper_twice_area(v, &e.normal);
            if (twice_area == 0.0) continue;  // degenerate
            e.vertices = v;
            e.radiance = *m.emission;
            e.area = 0.5 * twice_area;
            e.mesh = id;
            e.triangle = t;
            out.push_back(e);
        }
    }
    return out;
}

}  // namespace omis
