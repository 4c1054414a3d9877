#include "render/scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omis {

std::uint32_t Scene::add_mesh(const MeshInput& mesh) {
    if (committed_) throw std::logic_error("scene: already committed; add meshes before commit");
    return geometry_.add_mesh(mesh);
}

std::uint32_t Scene::add_mesh(const std::vector<Vec3>& positions,
                              const std::vector<std::array<std::uint32_t, 3>>& triangles,
                              std::optional<Vec3> emission) {
    if (committed_) throw std::logic_error("scene: already committed; add meshes before commit");
    return geometry_.add_mesh(positions, triangles, emission);
}

std::uint32_t Scene::add_light(const Light& light) {
    if (committed_) throw std::logic_error("scene: already committed; add lights before commit");
    if (light.type == LightType::World) {
        for (std::size_t i = 0; i < lights_.size(); ++i)
            if (lights_[i].type == LightType::World) {
                lights_[i] = light;
                return std::uint32_t(i);
            }
    }
    lights_.push_back(light);
    return std::uint32_t(lights_.size() - 1);
}

void Scene::require_uncommitted_light(std::uint32_t light) const {
    if (committed_) throw std::logic_error("scene: already committed; set flags before commit");
    if (light >= lights_.size())
        throw std::invalid_argument("light: id " + std::to_string(light) + " is out of range (" +
                                    std::to_string(lights_.size()) + " lights)");
}

void Scene::set_light_flags(std::uint32_t light, bool cast_shadow, bool visible_to_bsdf) {
    require_uncommitted_light(light);
    lights_[light].cast_shadow = cast_shadow;
    lights_[light].visible_to_bsdf = visible_to_bsdf;
}

void Scene::set_mesh_receiver(std::uint32_t mesh, const Receiver& receiver) {
    if (committed_) throw std::logic_error("scene: already committed; set receivers before commit");
    if (mesh >= geometry_.num_meshes())
        throw std::invalid_argument("mesh: id " + std::to_string(mesh) + " is out of range (" +
                                    std::to_string(geometry_.num_meshes()) + " meshes)");
    if (receivers_.size() <= mesh) receivers_.resize(mesh + 1);
    receivers_[mesh] = make_receiver(receiver.model, receiver.roughness);  // validates
}

const Receiver& Scene::mesh_receiver(std::uint32_t mesh) const {
    static const Receiver lambert;
    return mesh < receivers_.size() ? receivers_[mesh] : lambert;
}

void Scene::set_mesh_name(std::uint32_t mesh, const std::string& name) {
    geometry_.set_mesh_name(mesh, name);
}

void Scene::set_mesh_lights(bool on) {
    if (committed_) throw std::logic_error("scene: already committed; set mesh lights before commit");
    mesh_lights_ = on;
}

namespace {

// The emissive meshes commit() draws as one light each (Scene::set_mesh_lights),
// with their lights: a sphere holding each (about its box's centre, grown
// a little past single precision's rounding of the vertices Embree
// intersects) and its area.
std::vector<Light> mesh_lights_of(const GeometryScene& geometry,
                                  const std::vector<EmissiveTriangle>& emissive) {
    const std::size_t meshes = geometry.num_meshes();
    std::vector<double> area(meshes, 0);
    std::vector<std::size_t> count(meshes, 0);
    std::vector<Vec3> lo(meshes, Vec3(INFINITY, INFINITY, INFINITY)),
        hi(meshes, Vec3(-INFINITY, -INFINITY, -INFINITY));
    for (const EmissiveTriangle& t : emissive) {
        area[t.mesh] += t.area;
        ++count[t.mesh];
        for (const Vec3& v : t.vertices) {
            lo[t.mesh] = component_min(lo[t.mesh], v);
            hi[t.mesh] = component_max(hi[t.mesh], v);
        }
    }
    std::vector<double> radius2(meshes, 0);
    for (const EmissiveTriangle& t : emissive) {
        const Vec3 centre = (lo[t.mesh] + hi[t.mesh]) * 0.5;
        for (const Vec3& v : t.vertices)
            radius2[t.mesh] = std::max(radius2[t.mesh], dot(v - centre, v - centre));
    }
    // Mesh lights are unshaped (each direction tests every one's sphere):
    // the most triangles first, up to kMostMeshLights; the rest keep a light
    // per triangle, which the light tree and the emitter query scale to.
    std::vector<std::uint32_t> order(meshes);
    for (std::uint32_t m = 0; m < meshes; ++m) order[m] = m;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return count[a] > count[b]; });
    std::vector<Light> lights;
    for (std::uint32_t m : order) {
        if (lights.size() == Scene::kMostMeshLights) break;
        if (count[m] < Scene::kMeshLightTriangles || !(radius2[m] > 0)) continue;
        const Vec3 centre = (lo[m] + hi[m]) * 0.5;
        const double span = std::max({std::abs(centre.x), std::abs(centre.y), std::abs(centre.z)});
        const double radius = std::sqrt(radius2[m]) * (1 + 1e-5) + 1e-6 * span;
        if (area[m] < Scene::kMeshLightFill * 4 * kPi * radius * radius) continue;
        lights.push_back(make_mesh_light(m, centre, radius, area[m],
                                         *geometry.mesh(m).emission));
    }
    return lights;
}

}  // namespace

void Scene::commit() {
    if (committed_) return;
    analytic_lights_ = lights_.size();

    double r2 = 1.0;
    auto grow = [&](const Vec3& p) { r2 = std::max(r2, dot(p, p)); };
    for (const Mesh& mesh : geometry_.meshes())
        for (const Vec3& p : mesh.positions) grow(p);
    for (const Light& l : lights_) {
        switch (l.type) {
            case LightType::Rect: grow(l.rect.corner + l.rect.edge_u + l.rect.edge_v); grow(l.rect.corner); break;
            case LightType::Ellipse:
                for (double a : {-1.0, 1.0})
                    for (double b : {-1.0, 1.0})
                        grow(l.ellipse.center + l.ellipse.axis_a * a + l.ellipse.axis_b * b);
                break;
            case LightType::Point:
            case LightType::Spot: {
                const double r = std::sqrt(dot(l.position, l.position)) + l.radius;
                r2 = std::max(r2, r * r);
                break;
            }
            default: break;
        }
    }
    bounding_radius_ = std::sqrt(r2);

    // Emissive meshes emit from both sides, as Cycles' Emission shader does.
    const std::vector<EmissiveTriangle> emissive = geometry_.emissive_triangles();
    std::vector<bool> whole(geometry_.num_meshes(), false);  // drawn as a mesh light
    if (mesh_lights_)
        for (const Light& l : mesh_lights_of(geometry_, emissive)) {
            lights_.push_back(l);
            whole[l.mesh] = true;
            light_meshes_.push_back(l.mesh);
        }
    lights_.reserve(lights_.size() + emissive.size());  // Lights are large: no growth copies
    for (const EmissiveTriangle& t : emissive) {
        if (whole[t.mesh]) continue;
        Light light = make_triangle_light(t.vertices[0], t.vertices[1], t.vertices[2],
                                          t.radiance, /*two_sided=*/true);
        light.mesh = t.mesh;
        light.mesh_triangle = t.triangle;
        lights_.push_back(light);
    }
    light_powers_.reserve(lights_.size());
    for (const Light& l : lights_) light_powers_.push_back(l.power(bounding_radius_));
    build_emitter_shapes();
    geometry_.commit();  // with the emitter candidates (build_emitter_shapes)
    committed_ = true;
}

void Scene::build_emitter_shapes() {
    for (std::uint32_t id = 0; id < lights_.size(); ++id) {
        const Light& l = lights_[id];
        if (l.is_delta()) continue;
        switch (l.type) {
            case LightType::Rect: {
                const RectLight& r = l.rect;
                const Vec3 far = r.corner + r.edge_u + r.edge_v;
                emitter_shapes_.add_triangle(id, r.corner, r.corner + r.edge_u, far);
                emitter_shapes_.add_triangle(id, r.corner, far, r.corner + r.edge_v);
                break;
            }
            case LightType::Ellipse: {  // its bounding parallelogram
                const EllipseLight& e = l.ellipse;
                const Vec3 a = e.center - e.axis_a - e.axis_b, b = e.center + e.axis_a - e.axis_b,
                           c = e.center + e.axis_a + e.axis_b, d = e.center - e.axis_a + e.axis_b;
                emitter_shapes_.add_triangle(id, a, b, c);
                emitter_shapes_.add_triangle(id, a, c, d);
                break;
            }
            case LightType::Triangle:
                emitter_shapes_.add_triangle(id, l.triangle.p0, l.triangle.p1, l.triangle.p2);
                break;
            default: unshaped_lights_.push_back(id);
        }
    }
    // Light samples among emissive triangles trace the candidates with the
    // meshes (integrand.cpp: Integrand::to_blocker).
    // An emissive mesh's triangles are their own candidates there (their
    // hits name their lights): only the other shapes are added.
    if (std::any_of(geometry_.meshes().begin(), geometry_.meshes().end(),
                    [](const Mesh& m) { return m.is_emissive(); })) {
        const std::vector<float>& all = emitter_shapes_.enlarged_vertices();
        const std::vector<std::uint32_t>& light_of = emitter_shapes_.light_of();
        std::vector<float> vertices;
        std::vector<std::uint32_t> candidate_light_of;
        std::vector<GeometryScene::MeshTriangleLight> mesh_lights;
        for (std::size_t i = 0; i < light_of.size(); ++i) {
            const Light& l = lights_[light_of[i]];
            if (l.mesh != ~0u) {
                mesh_lights.push_back({l.mesh, l.mesh_triangle, light_of[i]});
                continue;
            }
            vertices.insert(vertices.end(), all.begin() + 9 * i, all.begin() + 9 * (i + 1));
            candidate_light_of.push_back(light_of[i]);
        }
        geometry_.set_emitter_candidates(vertices, std::move(candidate_light_of), mesh_lights,
                                         light_meshes_);
    }
    emitter_shapes_.commit();
}

const LightSelector& Scene::light_selector(LightSelector::Kind kind, bool delta) const {
    if (!committed_) throw std::logic_error("scene: not committed (light selection)");
    std::lock_guard<std::mutex> lock(selectors_mutex_);
    std::unique_ptr<LightSelector>& slot = selectors_[delta ? 1 : 0][int(kind)];
    if (!slot) {
        std::vector<std::uint32_t> ids;
        for (std::uint32_t l = 0; l < lights_.size(); ++l)
            if (lights_[l].is_delta() == delta) ids.push_back(l);
        slot = std::make_unique<LightSelector>(kind, lights_, ids, bounding_radius_);
    }
    return *slot;
}

std::optional<Scene::PassCost> Scene::measured_pass_cost(std::uint64_t bake_shape) const {
    std::lock_guard<std::mutex> lock(pass_costs_mutex_);
    const auto it = pass_costs_.find(bake_shape);
    if (it == pass_costs_.end()) return std::nullopt;
    return it->second;
}

void Scene::remember_pass_cost(std::uint64_t bake_shape, const PassCost& cost) const {
    // A few shapes per scene in practice (a mesh at one or two sizes); the
    // bound keeps a script baking thousands of shapes from growing it.
    constexpr std::size_t kMostShapes = 256;
    std::lock_guard<std::mutex> lock(pass_costs_mutex_);
    if (pass_costs_.size() >= kMostShapes && !pass_costs_.count(bake_shape)) pass_costs_.clear();
    pass_costs_[bake_shape] = cost;
}

}  // namespace omis
