// Mesh lights (Scene::set_mesh_lights, LightType::Mesh): a compact emissive
// mesh drawn as one light through its bounding sphere's cone, its radiance
// taken from the closest hit along each direction. Which meshes become one,
// their sampler and density (the checker of sampler_check.h), and — the key
// test — that the direct lighting they give is the per-triangle lights' (the
// same scene built both ways), and that they give it with much less noise.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "lights/light.h"
#include "render/direct_lighting.h"
#include "render/effect_plan.h"
#include "sampler_check.h"
#include "sampling/irradiance.h"
#include "support/emissive_sphere.h"
#include "support/lighting_settings.h"
#include "support/point_copies.h"

using namespace omis;
using omis::testing::add_emissive_sphere;

namespace {

const Vec3 kUp(0, 0, 1);

std::size_t count_of(const Scene& scene, LightType type) {
    return std::size_t(std::count_if(scene.lights().begin(), scene.lights().end(),
                                     [&](const Light& l) { return l.type == type; }));
}

// A flat n × n grid of emissive quads (2n² triangles) at height z: many
// triangles, but a small part of its bounding sphere's area.
void add_emissive_grid(Scene& scene, int n, double z) {
    std::vector<Vec3> p;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) p.push_back({double(i) / n, double(j) / n, z});
    std::vector<std::array<std::uint32_t, 3>> t;
    const auto at = [&](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    scene.add_mesh(p, t, Vec3(2, 2, 2));
}

// A closed box of 12 triangles, emissive.
void add_emissive_box(Scene& scene, const Vec3& lo, const Vec3& hi) {
    std::vector<Vec3> c;
    for (int i = 0; i < 8; ++i)
        c.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
    scene.add_mesh(c, {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                       {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}},
                   Vec3(2, 2, 2));
}

}  // namespace

TEST_CASE("mesh lights: which emissive meshes become one", "[lights][mesh_lights]") {
    SECTION("a UV sphere of 528 triangles: one mesh light, no triangle lights") {
        for (bool on : {true, false}) {
            Scene scene;
            add_emissive_sphere(scene, Vec3(0.2, -0.1, 1), 0.4, 12, 24, Vec3(1, 2, 3));
            if (!on) scene.set_mesh_lights(false);
            scene.commit();
            INFO("mesh lights " << (on ? "on" : "off"));
            if (on) {
                REQUIRE(scene.lights().size() == 1);
                const Light& l = scene.lights()[0];
                CHECK(l.type == LightType::Mesh);
                CHECK(l.mesh == 0);
                CHECK(l.two_sided);
                CHECK(l.emission.y == 2);
                // The box of a UV sphere with a pole on +z and vertices at
                // φ = 0, 90°, ... is the sphere's: centre and radius (grown
                // a little, to hold the vertices Embree rounds).
                CHECK(length(l.position - Vec3(0.2, -0.1, 1)) <= 1e-12);
                CHECK(l.radius >= 0.4);
                CHECK(l.radius <= 0.4 * (1 + 1e-4));
            } else {
                CHECK(scene.lights().size() == 528);
                CHECK(count_of(scene, LightType::Triangle) == 528);
            }
        }
    }
    SECTION("at the thresholds: 64 triangles and 75 % of the sphere's area") {
        // (stacks, slices) → triangles 2·slices·(stacks − 1), and their area
        // over their bounding sphere's (computed aside for unit spheres):
        // 5 × 8: 64, 0.90 → one light; 6 × 6: 60, 0.88 → too few triangles;
        // 2 × 32 (a double cone): 64, 0.70 → too little area.
        struct Case {
            int stacks, slices;
            bool mesh_light;
        };
        for (const Case c : {Case{5, 8, true}, Case{6, 6, false}, Case{2, 32, false}}) {
            Scene scene;
            add_emissive_sphere(scene, Vec3(0, 0, 1), 0.5, c.stacks, c.slices);
            scene.commit();
            INFO(c.stacks << " × " << c.slices);
            const std::size_t triangles = std::size_t(2 * c.slices * (c.stacks - 1));
            CHECK(count_of(scene, LightType::Mesh) == (c.mesh_light ? 1u : 0u));
            CHECK(count_of(scene, LightType::Triangle) == (c.mesh_light ? 0u : triangles));
        }
    }
    SECTION("a flat grid of 200 triangles and a box of 12 stay per-triangle") {
        Scene scene;
        add_emissive_grid(scene, 10, 1.5);
        add_emissive_box(scene, Vec3(-1, -1, 0.2), Vec3(-0.5, -0.5, 0.7));
        add_emissive_sphere(scene, Vec3(2, 0, 1), 0.3, 8, 16);  // 224 triangles: one light
        scene.commit();
        CHECK(count_of(scene, LightType::Mesh) == 1);
        CHECK(count_of(scene, LightType::Triangle) == 200 + 12);
        // Mesh lights come before the triangle lights (Scene::lights).
        CHECK(scene.lights()[0].type == LightType::Mesh);
        CHECK(scene.lights()[0].mesh == 2);
    }
    SECTION("set_mesh_lights after commit throws") {
        Scene scene;
        add_emissive_sphere(scene, Vec3(0, 0, 1), 0.3, 8, 16);
        scene.commit();
        CHECK_THROWS_AS(scene.set_mesh_lights(false), std::logic_error);
        CHECK_THROWS_AS(scene.set_mesh_lights(true), std::logic_error);
        CHECK(count_of(scene, LightType::Mesh) == 1);
    }
    SECTION("its power is its triangles'") {
        // With an analytic light first, so that the mesh light is not light 0.
        Scene on, off;
        for (Scene* s : {&on, &off}) {
            s->add_light(make_rect_light(Vec3(-1, -1, 3), Vec3(0, 2, 0), Vec3(2, 0, 0),
                                         Vec3(5, 5, 5), false, kPi));
            add_emissive_sphere(*s, Vec3(0.3, 0.1, 1), 0.35, 16, 32, Vec3(3.0, 2.55, 2.1));
        }
        off.set_mesh_lights(false);
        on.commit();
        off.commit();
        REQUIRE(on.lights().size() == 2);
        REQUIRE(on.lights()[1].type == LightType::Mesh);
        double triangles = 0, area = 0;
        for (std::size_t l = 1; l < off.lights().size(); ++l) {
            REQUIRE(off.lights()[l].type == LightType::Triangle);
            triangles += off.lights()[l].power(off.bounding_radius());
            area += off.lights()[l].triangle.area();
        }
        const double mesh = on.lights()[1].power(on.bounding_radius());
        CHECK(std::abs(mesh - triangles) <= 1e-9 * triangles);
        CHECK(std::abs(on.light_powers()[1] - triangles) <= 1e-9 * triangles);
        CHECK(std::abs(on.lights()[1].mesh_area - area) <= 1e-9 * area);
    }
}

// The mesh light's sampler through the light dispatch, for every shape
// sampler (a mesh light ignores which: each draws the cone, or the cosine
// hemisphere inside the sphere), against exact cell probabilities: cells of
// equal probability, bands equal in 1 − cos θ across the cone (uniform in
// solid angle) or in sin²θ across the hemisphere (the cosine density), times
// equal sectors of φ.
namespace {

constexpr int kCells = 8;

// The cell of w in K bands of `band(w)` ∈ [0, 1] times K sectors of φ about
// the frame's normal; −1 outside [0, 1].
int cell_of(const Frame& frame, const Vec3& w, double band) {
    if (!(band >= -1e-12 && band <= 1 + 1e-9)) return -1;
    const Vec3 l = frame.to_local(w);
    double phi = std::atan2(l.y, l.x) / (2 * kPi);
    if (phi < 0) phi += 1;
    const int i = std::clamp(int(band * kCells), 0, kCells - 1);
    const int j = std::clamp(int(phi * kCells), 0, kCells - 1);
    return i * kCells + j;
}

}  // namespace

TEST_CASE("mesh lights: sample_light and light_pdf agree", "[lights][mesh_lights]") {
    const ShapeSampler samplers[] = {ShapeSampler::Area, ShapeSampler::SolidAngle,
                                     ShapeSampler::Parallel, ShapeSampler::ProjectedSolidAngle};
    const Vec3 centre(0.3, 0.2, 1.5);
    const double r = 0.4;
    const Light light = make_mesh_light(0, centre, r, 0.9 * 4 * kPi * r * r, Vec3(1, 1, 1));
    struct Case {
        const char* what;
        Vec3 x, n;
        bool cone;
    };
    const Vec3 toward = normalize(centre);
    const Case cases[] = {
        {"far above", Vec3(0, 0, 0), kUp, true},
        {"straddling the horizon", centre - Vec3(1.2, 0, 0.1), kUp, true},
        {"tilted receiver, close", centre - 1.05 * r * toward, normalize(Vec3(1, 0, 1)), true},
        // Within the margin of mesh_light_draws_cone (1e-4 of r): cosine.
        {"on the sphere", centre - r * toward, normalize(Vec3(0.2, -0.3, 1)), false},
        {"just outside, within the margin", centre - r * (1 + 5e-5) * toward, kUp, false},
        {"inside, at the centre", centre, normalize(Vec3(-0.5, 0.1, 0.3)), false},
    };
    std::uint64_t seed = 91000;
    for (const Case& c : cases) {
        CHECK(mesh_light_draws_cone(light, c.x) == c.cone);
        // The reference, from the geometry alone: the cone's axis and
        // cos θmax = √(1 − r²/d²), or the hemisphere about n.
        const Vec3 d = centre - c.x;
        const double cos_max = std::sqrt(std::max(0.0, 1 - r * r / dot(d, d)));
        const Frame frame(c.cone ? normalize(d) : c.n);
        const double measure = c.cone ? 2 * kPi * (1 - cos_max) : 2 * kPi;
        for (ShapeSampler s : samplers) {
            INFO(c.what << ", " << shape_sampler_name(s));
            CHECK(sampler_applies(light, s, c.x, c.n));
            testing::SamplerUnderTest t;
            t.name = std::string(c.what) + ", " + shape_sampler_name(s);
            t.sample = [&](double u1, double u2) { return sample_light(light, s, c.x, c.n, u1, u2); };
            t.pdf = [&](const Vec3& w) { return light_pdf(light, s, c.x, c.n, w); };
            t.bin = [&](const Vec3& w) {
                const double z = dot(frame.n, w);
                return cell_of(frame, w, c.cone ? (1 - z) / (1 - cos_max) : 1 - z * z);
            };
            t.cell_prob.assign(kCells * kCells, 1.0 / (kCells * kCells));
            t.measure = measure;
            t.finite_dist = false;  // the first hit decides
            // 1/pdf is constant on the cone (σ = 0: the checker's relative
            // floor, 1e-8, bounds the two formulas' rounding). On the
            // hemisphere it is π/cos θ, whose variance is infinite: no
            // normal band for its mean, so the mean check is off there; the
            // densities are checked pointwise below instead.
            t.check_mean = c.cone;
            testing::run_sampler_check(t, seed++);

            // Densities off the draws: the cone's constant inside, 0 just
            // outside it; the cosine's cos θ/π, 0 below the horizon.
            if (c.cone) {
                const double sin_out = std::sqrt(1 - cos_max * cos_max) * 1.001;
                const double sin_in = std::sqrt(1 - cos_max * cos_max) * 0.999;
                for (double sin_t : {sin_in, sin_out}) {
                    const Vec3 w =
                        frame.to_world(Vec3(sin_t, 0, std::sqrt(std::max(0.0, 1 - sin_t * sin_t))));
                    const double expected = sin_t == sin_in ? 1 / measure : 0.0;
                    CHECK(std::abs(light_pdf(light, s, c.x, c.n, w) - expected) <=
                          1e-9 / measure);
                }
            } else {
                for (const Vec3& local : {Vec3(0.6, 0, 0.8), Vec3(0, 0.8, -0.6), Vec3(0, 0, 1)}) {
                    const Vec3 w = frame.to_world(local);
                    CHECK(std::abs(light_pdf(light, s, c.x, c.n, w) -
                                   std::max(0.0, local.z) / kPi) <= 1e-12);
                }
            }
        }
    }
}
