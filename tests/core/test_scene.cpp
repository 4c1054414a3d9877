// Embree geometry: occlusion/intersection queries, validation, ray counting,
// thread safety, a large mesh, and self-intersection avoidance.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <thread>

#include "scene/geometry_scene.h"
#include "scene/ray_offset.h"

using namespace omis;
using Tri = std::array<std::uint32_t, 3>;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Unit square in z = 0, normal +z: triangles (0,1,2) below the diagonal y = x
// and (0,2,3) above it.
const std::vector<Vec3> kQuadV = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
const std::vector<Tri> kQuadT = {{0, 1, 2}, {0, 2, 3}};

std::string message_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const std::exception& e) {
        return e.what();
    }
    return "<no exception>";
}

}  // namespace

TEST_CASE("unit quad occludes rays through it and not beside it", "[scene]") {
    GeometryScene scene;
    scene.add_mesh(kQuadV, kQuadT);
    scene.commit();
    REQUIRE(scene.has_occluders());

    const Vec3 down{0, 0, -1};
    CHECK(scene.occluded({0.5, 0.5, 1}, down, 0, kInf));
    CHECK(scene.occluded({0.1, 0.8, 1}, down, 0, 2));
    CHECK(scene.occluded({0.9, 0.2, -1}, -down, 0, 2));  // back face occludes too
    CHECK_FALSE(scene.occluded({1.5, 0.5, 1}, down, 0, kInf));
    CHECK_FALSE(scene.occluded({-0.01, 0.5, 1}, down, 0, kInf));
    CHECK_FALSE(scene.occluded({0.5, 0.5, 1}, -down, 0, kInf));  // pointing away
    // Oblique ray through the quad.
    CHECK(scene.occluded({-1, 0.5, 1}, Vec3{1.5, 0, -1}, 0, kInf));
}

TEST_CASE("tmin and tmax bound the ray", "[scene]") {
    GeometryScene scene;
    scene.add_mesh(kQuadV, kQuadT);
    scene.commit();
    const Vec3 o{0.5, 0.5, 1}, d{0, 0, -1};
    CHECK(scene.occluded(o, d, 0, 1.001));
    CHECK_FALSE(scene.occluded(o, d, 0, 0.999));
    CHECK_FALSE(scene.occluded(o, d, 1.001, 5));
    CHECK(scene.occluded(o, d, 0.999, 5));
    // t is measured in units of the (non-unit) direction.
    CHECK_FALSE(scene.occluded(o, d * 4.0, 0, 0.24));
    CHECK(scene.occluded(o, d * 4.0, 0, 0.26));
    // Empty or invalid intervals trace nothing.
    scene.reset_ray_count();
    CHECK_FALSE(scene.occluded(o, d, 2, 1));
    CHECK_FALSE(scene.occluded(o, d, 0, std::nan("")));
    CHECK(scene.rays_traced() == 0);
    REQUIRE_FALSE(scene.intersect(o, d, 0, 0.999).has_value());
}

TEST_CASE("intersect returns t, ids, barycentrics and normal", "[scene]") {
    GeometryScene scene;
    const auto far_id = scene.add_mesh({{0, 0, -5}, {1, 0, -5}, {0, 1, -5}}, {{0, 1, 2}});
    const auto quad_id = scene.add_mesh(kQuadV, kQuadT, std::nullopt, "quad");
    REQUIRE(far_id == 0);
    REQUIRE(quad_id == 1);
    scene.commit();

    // Above the diagonal: triangle 1 = (v0, v2, v3); p = b1*(1,1) + b2*(0,1).
    auto hit = scene.intersect({0.25, 0.5, 2}, {0, 0, -2}, 0, kInf);
    REQUIRE(hit);
    CHECK(hit->t == Approx(1.0).epsilon(1e-6));
    CHECK(hit->mesh == quad_id);
    CHECK(hit->triangle == 1);
    CHECK(hit->b1 == Approx(0.25).epsilon(1e-6));
    CHECK(hit->b2 == Approx(0.25).epsilon(1e-6));
    CHECK(hit->geometric_normal.z == Approx(1.0));
    CHECK(hit->position.x == Approx(0.25));
    CHECK(hit->position.y == Approx(0.5));
    CHECK(hit->position.z == Approx(0.0).margin(1e-12));

    // Below the diagonal: triangle 0 = (v0, v1, v2); p = b1*(1,0) + b2*(1,1).
    hit = scene.intersect({0.75, 0.25, 1}, {0, 0, -1}, 0, kInf);
    REQUIRE(hit);
    CHECK(hit->triangle == 0);
    CHECK(hit->b1 == Approx(0.5).epsilon(1e-6));
    CHECK(hit->b2 == Approx(0.25).epsilon(1e-6));

    // Starting past the quad, the far triangle is next; the normal keeps its
    // winding orientation (+z) although the ray comes from above.
    hit = scene.intersect({0.2, 0.2, 1}, {0, 0, -1}, 1.5, kInf);
    REQUIRE(hit);
    CHECK(hit->mesh == far_id);
    CHECK(hit->triangle == 0);
    CHECK(hit->t == Approx(6.0));
    CHECK(hit->geometric_normal.z == Approx(1.0));

    CHECK_FALSE(scene.intersect({2, 2, 1}, {0, 0, -1}, 0, kInf).has_value());
}

TEST_CASE("invalid meshes raise with clear messages", "[scene]") {
    GeometryScene scene;
    using Catch::Matchers::Contains;

    CHECK_THAT(message_of([&] { scene.add_mesh({}, {}); }), Contains("empty mesh"));
    CHECK_THAT(message_of([&] { scene.add_mesh(kQuadV, {}); }), Contains("empty mesh"));
    CHECK_THAT(message_of([&] { scene.add_mesh(kQuadV, {{0, 1, 2}, {0, 2, 7}}, {}, "bad"); }),
               Contains("triangle 1 = (0, 2, 7)") && Contains("out of range") &&
                   Contains("'bad'"));
    auto v = kQuadV;
    v[2].y = std::nan("");
    CHECK_THAT(message_of([&] { scene.add_mesh(v, kQuadT); }),
               Contains("vertex 2 is not finite"));
    v[2].y = kInf;
    CHECK_THAT(message_of([&] { scene.add_mesh(v, kQuadT); }),
               Contains("vertex 2 is not finite"));
    CHECK_THAT(message_of([&] { scene.add_mesh(kQuadV, kQuadT, Vec3{1, -1, 0}); }),
               Contains("emission"));

    // Wrong shapes through the array interface.
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const std::uint32_t idx[] = {0, 1, 2};
    MeshInput in;
    in.positions = ScalarArray::of(pos, 3, 3);
    in.triangles = {idx, 1, 3};
    MeshInput bad = in;
    bad.positions = ScalarArray::of(pos, 4, 2);
    CHECK_THAT(message_of([&] { scene.add_mesh(bad); }),
               Contains("positions must have shape (V, 3), got (4, 2)"));
    bad = in;
    bad.triangles = {idx, 3, 1};
    CHECK_THAT(message_of([&] { scene.add_mesh(bad); }), Contains("triangles must have shape"));
    const double normals[] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    bad = in;
    bad.normals = ScalarArray::of(normals, 1, 3);  // per vertex of one triangle? no: per corner
    CHECK_THAT(message_of([&] { scene.add_mesh(bad); }),
               Contains("normals must be per corner with shape (3T, 3) = (3, 3), got (1, 3)"));
    bad = in;
    bad.uvs = ScalarArray::of(normals, 3, 3);
    CHECK_THAT(message_of([&] { scene.add_mesh(bad); }), Contains("uvs must be per corner"));
    const double nan_normals[] = {0, 0, 1, 0, std::nan(""), 1, 0, 0, 1};
    bad = in;
    bad.normals = ScalarArray::of(nan_normals, 3, 3);
    CHECK_THAT(message_of([&] { scene.add_mesh(bad); }),
               Contains("normal of corner 1 (triangle 0) is not finite"));

    // Exception types: validation is std::invalid_argument.
    CHECK_THROWS_AS(scene.add_mesh({}, {}), std::invalid_argument);
    CHECK(scene.num_meshes() == 0);  // nothing half-added

    // The valid float input is accepted.
    CHECK(scene.add_mesh(in) == 0);
}

TEST_CASE("degenerate triangles are counted and allowed", "[scene]") {
    GeometryScene scene;
    const std::vector<Vec3> v = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
    const auto id = scene.add_mesh(v, {{0, 1, 2}, {0, 0, 3}, {0, 1, 3}});
    CHECK(scene.mesh(id).degenerate_triangles == 2);
    CHECK(scene.mesh(id).area == Approx(0.5));
    scene.commit();
    CHECK(scene.has_occluders());
    CHECK(scene.occluded({0.2, 0.2, 1}, {0, 0, -1}, 0, kInf));

    GeometryScene only_degenerate;
    only_degenerate.add_mesh(v, {{0, 1, 2}});
    only_degenerate.commit();
    CHECK_FALSE(only_degenerate.has_occluders());
}

TEST_CASE("queries need a committed scene", "[scene]") {
    GeometryScene scene;
    scene.add_mesh(kQuadV, kQuadT);
    CHECK_THROWS_AS(scene.occluded({0, 0, 1}, {0, 0, -1}, 0, 1), std::logic_error);
    CHECK_THROWS_WITH(scene.intersect({0, 0, 1}, {0, 0, -1}, 0, 1),
                      Catch::Contains("not committed"));
    scene.commit();
    CHECK(scene.occluded({0.5, 0.5, 1}, {0, 0, -1}, 0, 2));
    scene.add_mesh({{5, 5, 5}, {6, 5, 5}, {5, 6, 5}}, {{0, 1, 2}});  // un-commits
    CHECK_FALSE(scene.committed());
    CHECK_THROWS_AS(scene.occluded({0, 0, 1}, {0, 0, -1}, 0, 1), std::logic_error);
    scene.commit();
    CHECK(scene.occluded({5.2, 5.2, 6}, {0, 0, -1}, 0, 2));
}

TEST_CASE("a scene without geometry traces zero rays", "[scene]") {
    GeometryScene scene;
    scene.commit();
    CHECK_FALSE(scene.has_occluders());
    for (int i = 0; i < 100; ++i) {
        CHECK_FALSE(scene.occluded({0, 0, double(i)}, {0, 0, -1}, 0, kInf));
        CHECK_FALSE(scene.intersect({0, 0, double(i)}, {0, 0, -1}, 0, kInf));
    }
    std::vector<Ray> rays(10, Ray{{0, 0, 1}, {0, 0, -1}, 0, kInf});
    bool out[10] = {true, true, true, true, true, true, true, true, true, true};
    scene.occluded(rays.data(), rays.size(), out);
    for (bool o : out) CHECK_FALSE(o);
    CHECK(scene.rays_traced() == 0);
}

TEST_CASE("rays traced are counted across threads", "[scene]") {
    GeometryScene scene;
    scene.add_mesh(kQuadV, kQuadT);
    scene.commit();
    constexpr int kPerThread = 20000;
    int wrong[2] = {0, 0};
    auto work = [&](int which) {
        std::mt19937 rng(1234 + which);
        std::uniform_real_distribution<double> u(-0.5, 1.5);
        for (int i = 0; i < kPerThread; ++i) {
            const double x = u(rng), y = u(rng);
            const bool inside = x >= 0 && x <= 1 && y >= 0 && y <= 1;
            if (std::abs(x) < 1e-4 || std::abs(x - 1) < 1e-4 || std::abs(y) < 1e-4 ||
                std::abs(y - 1) < 1e-4) {
                scene.occluded({x, y, 1}, {0, 0, -1}, 0, 2);  // edge: either answer
                continue;
            }
            if (which == 0) {
                if (scene.occluded({x, y, 1}, {0, 0, -1}, 0, 2) != inside) ++wrong[which];
            } else {
                const auto hit = scene.intersect({x, y, 1}, {0, 0, -1}, 0, 2);
                if (hit.has_value() != inside ||
                    (hit && std::abs(hit->t - 1.0) > 1e-6))
                    ++wrong[which];
            }
        }
    };
    std::thread a(work, 0), b(work, 1);
    a.join();
    b.join();
    CHECK(wrong[0] == 0);
    CHECK(wrong[1] == 0);
    CHECK(scene.rays_traced() == 2u * kPerThread);
    scene.reset_ray_count();
    CHECK(scene.rays_traced() == 0);
}

namespace {
// N x N grid of quads over [0,1]^2 at height z, 2 N² triangles; cell (i, j)
// holds triangles 2(jN+i) (below its diagonal) and 2(jN+i)+1.
void make_grid(int N, double z, std::vector<Vec3>& v, std::vector<Tri>& t) {
    v.clear();
    t.clear();
    for (int j = 0; j <= N; ++j)
        for (int i = 0; i <= N; ++i) v.push_back({double(i) / N, double(j) / N, z});
    auto at = [&](int i, int j) { return std::uint32_t(j * (N + 1) + i); };
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
            t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
}

// A committed scene of one N × N grid at height 0.
std::unique_ptr<GeometryScene> grid_scene(int N) {
    std::vector<Vec3> v;
    std::vector<Tri> t;
    make_grid(N, 0, v, t);
    auto scene = std::make_unique<GeometryScene>();
    scene->add_mesh(v, t);
    scene->commit();
    return scene;
}
}  // namespace

TEST_CASE("a mesh of 100k+ triangles builds and answers", "[scene]") {
    constexpr int N = 256;  // 131072 triangles
    std::vector<Vec3> v;
    std::vector<Tri> t;
    make_grid(N, 0.25, v, t);
    GeometryScene scene;
    const auto t0 = std::chrono::steady_clock::now();
    scene.add_mesh(v, t);
    scene.commit();
    const double build_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    INFO("build of " << t.size() << " triangles: " << build_ms << " ms");
    REQUIRE(scene.mesh(0).num_triangles() == 131072);
    CHECK(scene.mesh(0).area == Approx(1.0));

    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0005, 0.9995);
    int wrong = 0;
    for (int k = 0; k < 2000; ++k) {
        const double x = u(rng), y = u(rng);
        const double fx = x * N - std::floor(x * N), fy = y * N - std::floor(y * N);
        if (std::abs(fx - fy) < 1e-3 || fx < 1e-3 || fy < 1e-3 || fx > 1 - 1e-3 || fy > 1 - 1e-3)
            continue;  // too close to an edge to insist on the triangle id
        const auto hit = scene.intersect({x, y, 1}, {0, 0, -1}, 0, kInf);
        const std::uint32_t cell = std::uint32_t(std::floor(y * N) * N + std::floor(x * N));
        const std::uint32_t expect = 2 * cell + (fy > fx ? 1 : 0);
        if (!hit || hit->triangle != expect || std::abs(hit->t - 0.75) > 1e-6 ||
            std::abs(hit->position.x - x) > 1e-6 || std::abs(hit->position.y - y) > 1e-6)
            ++wrong;
    }
    CHECK(wrong == 0);
    CHECK_FALSE(scene.occluded({0.5, 0.5, 1}, {0, 0, 1}, 0, kInf));
    CHECK(scene.occluded({0.5, 0.5, 1}, {0, 0, -1}, 0, kInf));
}

TEST_CASE("batch occlusion agrees with single rays", "[scene]") {
    const auto scene = grid_scene(32);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<Ray> rays(1000);
    for (auto& r : rays) {
        r.origin = {0.5 + u(rng), 0.5 + u(rng), 0.5 * u(rng)};
        // Aimed at a point of [-0.5, 1.5]^2 x {0}: about a quarter of the rays
        // reach the grid (t = 1) inside the interval.
        r.direction = Vec3{0.5 + u(rng), 0.5 + u(rng), 0} - r.origin;
        r.tmin = 0;
        r.tmax = 1 + u(rng);  // some empty intervals too
    }
    std::unique_ptr<bool[]> out(new bool[rays.size()]);
    scene->occluded(rays.data(), rays.size(), out.get());
    int disagree = 0, hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const auto& r = rays[i];
        disagree += out[i] != scene->occluded(r.origin, r.direction, r.tmin, r.tmax);
        hits += out[i];
    }
    CHECK(disagree == 0);
    CHECK(hits > 50);
}

TEST_CASE("offset ray origins do not self-intersect", "[scene]") {
    auto magnitude = GENERATE(1e-3, 1.0, 1e2, 1e4);
    // A large tilted triangle far from the origin: float rounding of the hit
    // point is at its worst there.
    const Vec3 c{magnitude, -0.7 * magnitude, 0.3 * magnitude};
    const double s = 0.5 * std::max(1.0, magnitude);
    const std::vector<Vec3> v = {c + Vec3{-s, -s, 0.2 * s}, c + Vec3{s, -0.3 * s, -s},
                                 c + Vec3{0.1 * s, s, 0.4 * s}};
    GeometryScene scene;
    scene.add_mesh(v, {{0, 1, 2}});
    scene.commit();
    const Vec3 ng = scene.mesh(0).geometric_normal(0);

    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0, 1);
    int self_hits = 0, real_misses = 0;
    double worst_offset = 0;
    for (int k = 0; k < 5000; ++k) {
        double b1 = u(rng), b2 = u(rng);
        if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
        // Start from the point Embree reports for a ray cast at the triangle.
        const Vec3 target = (1 - b1 - b2) * v[0] + b1 * v[1] + b2 * v[2];
        const Vec3 from = target + ng * (k % 2 ? 1.0 : -1.0) * s;
        const auto hit = scene.intersect(from, target - from, 0, kInf);
        if (!hit) continue;
        const Vec3 p = hit->position;
        // Random direction, half of them leaving through the other side.
        Vec3 d{u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5};
        const Vec3 o = offset_ray_origin(p, hit->geometric_normal, d);
        worst_offset = std::max(worst_offset, length(o - p) / std::max(1.0, length(p)));
        if (scene.occluded(o, d, 0, kInf)) ++self_hits;
        // A ray aimed back at the triangle from the offset point still hits it.
        if (!scene.occluded(offset_ray_origin(p, hit->geometric_normal, from - p),
                            (target - from) * 1.0, 0, kInf))
            ++real_misses;
    }
    INFO("magnitude " << magnitude << ", worst relative offset " << worst_offset);
    CHECK(self_hits == 0);
    CHECK(real_misses == 0);
    CHECK(worst_offset < 1e-4);
}

TEST_CASE("mesh accessors for baking and lights", "[scene]") {
    GeometryScene scene;
    const double normals[] = {0, 0, 1, 1, 0, 0, 0, 1, 0,  0, 0, 1, 0, 0, 1, 0, 0, 1};
    const float uvs[] = {0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1};
    std::vector<double> pos;
    for (const auto& p : kQuadV) pos.insert(pos.end(), {p.x, p.y, p.z});
    MeshInput in;
    in.name = "lamp";
    in.positions = ScalarArray::of(pos.data(), 4, 3);
    in.triangles = {kQuadT[0].data(), 2, 3};
    in.normals = ScalarArray::of(normals, 6, 3);
    in.uvs = ScalarArray::of(uvs, 6, 2);
    in.emission = Vec3{1, 2, 3};
    const auto lamp = scene.add_mesh(in);
    const auto plain = scene.add_mesh(kQuadV, kQuadT);
    const auto dark = scene.add_mesh(kQuadV, kQuadT, Vec3{0, 0, 0});
    scene.commit();

    const Mesh& m = scene.mesh(lamp);
    CHECK(m.name == "lamp");
    CHECK(m.has_normals());
    CHECK(m.has_uvs());
    CHECK(m.corner_uvs[2][0] == 1.0);
    CHECK(m.area == Approx(1.0));
    CHECK(m.is_emissive());
    const Vec3 n = m.shading_normal(0, 1.0 / 3, 1.0 / 3);
    CHECK(n.x == Approx(1 / std::sqrt(3.0)));
    CHECK(n.z == Approx(1 / std::sqrt(3.0)));

    CHECK_FALSE(scene.mesh(plain).has_normals());  // flat, not smoothed
    CHECK_FALSE(scene.mesh(plain).has_uvs());
    CHECK(scene.mesh(plain).shading_normal(1, 0.2, 0.2).z == Approx(1.0));
    CHECK_FALSE(scene.mesh(dark).is_emissive());  // zero emission is no light
    CHECK_THROWS_AS(scene.mesh(7), std::out_of_range);

    const auto lights = scene.emissive_triangles();
    REQUIRE(lights.size() == 2);
    double area = 0;
    for (const auto& e : lights) {
        CHECK(e.mesh == lamp);
        CHECK(e.radiance.y == 2.0);
        CHECK(e.normal.z == Approx(1.0));
        area += e.area;
    }
    CHECK(area == Approx(1.0));
    CHECK(lights[1].vertices[1].x == 1.0);  // triangle (0, 2, 3): vertex 2 = (1, 1, 0)
}

TEST_CASE("Embree errors become exceptions with Embree's message", "[scene]") {
    auto device = Device::shared();
    CHECK_NOTHROW(device->check());
    RTCGeometry g = rtcNewGeometry(device->handle(), RTCGeometryType(12345));
    if (g) rtcReleaseGeometry(g);
    REQUIRE(device->has_error());
    CHECK_THROWS_AS(device->check(), EmbreeError);
    CHECK_NOTHROW(device->check());  // cleared
    RTCScene s = rtcNewScene(device->handle());
    rtcSetSceneBuildQuality(s, RTCBuildQuality(99));
    rtcReleaseScene(s);
    CHECK_THROWS_WITH(device->check(), Catch::Contains("invalid build quality"));
}

TEST_CASE("scene occlusion throughput", "[.bench][scene]") {
    const auto scene = grid_scene(512);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<Ray> rays(1 << 20);
    for (auto& r : rays) {
        r.origin = {0.5 + u(rng), 0.5 + u(rng), 0.5 + 0.5 * u(rng)};
        r.direction = {u(rng), u(rng), u(rng)};
        r.tmax = 2;
    }
    std::unique_ptr<bool[]> out(new bool[rays.size()]);
    auto t0 = std::chrono::steady_clock::now();
    std::size_t hits = 0;
    for (auto& r : rays) hits += scene->occluded(r.origin, r.direction, r.tmin, r.tmax);
    auto t1 = std::chrono::steady_clock::now();
    scene->occluded(rays.data(), rays.size(), out.get());
    auto t2 = std::chrono::steady_clock::now();
    const double single = std::chrono::duration<double>(t1 - t0).count();
    const double batch = std::chrono::duration<double>(t2 - t1).count();
    std::printf("occluded x%zu (hits %zu): single %.1f Mrays/s, batch %.1f Mrays/s\n",
                rays.size(), hits, rays.size() / single * 1e-6, rays.size() / batch * 1e-6);
}
