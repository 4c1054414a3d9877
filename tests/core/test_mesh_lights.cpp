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
#include "support/square_footprint.h"

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

// A closed box of 12 triangles, emitting `emission` if given.
void add_box(Scene& scene, const Vec3& lo, const Vec3& hi,
             std::optional<Vec3> emission = Vec3(2, 2, 2)) {
    std::vector<Vec3> c;
    for (int i = 0; i < 8; ++i)
        c.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
    scene.add_mesh(c, {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                       {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}},
                   emission);
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
        add_box(scene, Vec3(-1, -1, 0.2), Vec3(-0.5, -0.5, 0.7));
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

TEST_CASE("mesh lights: which directions may see the mesh", "[lights][mesh_lights]") {
    // The whole cone of the bounding sphere, half-angle asin(r/d) = 30° here
    // (not the 26.6° of a disk of radius r facing x), and every direction
    // from inside the sphere or on it.
    const Light light = make_mesh_light(0, Vec3(0, 0, 2), 1.0, 10.0, Vec3(1, 1, 1));
    const auto at = [](double degrees) {
        const double a = degrees * kPi / 180;
        return Vec3(std::sin(a), 0, std::cos(a));
    };
    const Vec3 x(0, 0, 0);
    CHECK(mesh_light_along(light, x, at(0)));
    CHECK(mesh_light_along(light, x, at(28)));
    CHECK(mesh_light_along(light, x, at(29.9)));
    CHECK_FALSE(mesh_light_along(light, x, at(30.1)));
    CHECK_FALSE(mesh_light_along(light, x, at(180)));
    for (const Vec3& inside : {Vec3(0, 0, 2), Vec3(0, 0.5, 2.5), Vec3(0, 0, 1)}) {
        CHECK(mesh_light_along(light, inside, at(120)));
        CHECK(mesh_light_along(light, inside, at(-90)));
    }
}

// The key test: a scene drawn with a mesh light must be lit as with its
// triangles' lights (set_mesh_lights(false)), both being unbiased estimates
// of the same E/π. T copies of a receiver in one call are T independent
// estimates (testing::light_point_copies), whose spread gives each mean's
// standard error; the two builds use different seeds, so their means are
// independent and a − b has standard error √(σa² + σb²).
//
// kSigmas = 5: each scene compares 10–13 receivers under 11 configurations,
// ~470 comparisons in all. With σ measured from 256 copies, a − b over its
// standard error follows roughly Student's t with ≥ 250 degrees of freedom,
// whose two-sided tail beyond 5 is ~1e-6: ~0.05 % that any of them misses
// by chance (measured: the 471 z-scores have mean −0.04, spread 1.07, the
// largest 3.7). The estimates are not all normal (a few heavy-tailed per-
// triangle estimates near the sphere), which 5 rather than 4 also leaves
// room for. A bias shows where it exceeds 5 standard errors at one receiver,
// or, smaller but shared by many, in the aggregate below.
namespace {

constexpr double kSigmas = 5.0;
// The aggregate: Σz/√M over a scene's M comparisons (independent seeds) is
// ~N(0, 1); 4 of them (one per scene) at 4σ miss by chance with ~3e-4.
constexpr double kAggregateSigmas = 4.0;
constexpr int kCopies = 256;
constexpr int kRounds = 8;

struct Shading {
    const char* what;
    Vec3 x, n;
};

// How a receiver is shaded: the plan's default techniques for the scene (its
// own for each build, what a bake would use) or named ones.
struct Config {
    std::vector<std::string> names;  // empty: the plan's
    std::vector<int> samples;
    Strategy strategy;
    bool fast_paths;
    int rounds = kRounds;
};

const std::vector<Config>& configs() {
    static const std::vector<Config> all = [] {
        std::vector<Config> c;
        // Optimal: the cross-fitted one (optimal-direct, which solves from
        // the samples it weighs, is biased: mis/strategy.h), at 32 rounds.
        // Its correction is unbiased for independent rounds, not for one
        // Sobol' sequence's: at 8 rounds of power/area + bsdf, 1 cm from the
        // resting sphere's contact, the triangle lights' estimate stood 0.5 %
        // (~9σ of 512 copies) above the exact value (optimal-direct 0.7 %),
        // at 32 rounds 0.04 % (1.4σ), balance within 1σ at both; the mesh
        // light's within 2σ (of 256 copies) at 8 rounds.
        for (bool fast : {true, false})
            for (Strategy s : {Strategy::Balance, Strategy::OptimalProgressive}) {
                const int rounds = s == Strategy::Balance ? kRounds : 4 * kRounds;
                c.push_back({{}, {}, s, fast, rounds});
                c.push_back({{"power/area", "bsdf"}, {4, 4}, s, fast, rounds});
            }
        // The light tree's and the unoccluded irradiance's weights (a mesh
        // light's bounds and irradiance are its bounding sphere's).
        c.push_back({{"tree/solid-angle", "bsdf"}, {4, 4}, Strategy::Balance, true});
        c.push_back({{"unoccluded/solid-angle", "bsdf"}, {4, 4}, Strategy::Balance, true});
        // One light technique: each sample estimates its own light's part
        // (direct_lighting.cpp, light_integrand) where no triangle lights are.
        c.push_back({{"power/solid-angle"}, {8}, Strategy::Balance, true});
        return c;
    }();
    return all;
}

DirectLightingSettings settings_for(const Scene& scene, const Config& c, std::uint64_t seed) {
    DirectLightingSettings s;
    if (c.names.empty()) {
        default_techniques(scene, s.techniques, s.samples);
        s.rounds = c.rounds;
        s.strategy = c.strategy;
        s.seed = seed;
    } else {
        s = testing::lighting_settings(c.names, c.samples, c.rounds, c.strategy, seed);
    }
    s.fast_paths = c.fast_paths;
    return s;
}

std::string describe(const Scene& scene, const Config& c) {
    std::string s;
    for (const std::string& n : c.names.empty() ? testing::plan_names(scene) : c.names)
        s += n + " ";
    return s + strategy_name(c.strategy) + (c.fast_paths ? ", fast paths" : ", general path");
}

// E/π at x where a convex emissive mesh alone lights it, unoccluded: the
// faces turned toward x (every face, from inside), each clipped to x's
// horizon; a convex mesh's visible faces do not overlap. The faces are the
// per-triangle build's lights of that mesh.
double convex_mesh_exact(const Scene& triangles, std::uint32_t mesh, const Vec3& x,
                         const Vec3& n) {
    std::vector<const Light*> faces;
    for (const Light& l : triangles.lights())
        if (l.type == LightType::Triangle && l.mesh == mesh) faces.push_back(&l);
    const auto facing = [&](const Light* l) {
        const TriangleLight& t = l->triangle;
        return dot(cross(t.p1 - t.p0, t.p2 - t.p0), x - t.p0) > 0;
    };
    const bool inside = std::none_of(faces.begin(), faces.end(), facing);
    double e = 0;
    for (const Light* l : faces)
        if (inside || facing(l))
            e += l->emission.y *
                 polygon_irradiance(x, n, {l->triangle.p0, l->triangle.p1, l->triangle.p2}) / kPi;
    return e;
}

// Builds the scene twice (`build` adds everything but does not commit), with
// and without mesh lights, and compares them at every receiver under every
// configuration; where `exact_mesh` names a convex emissive mesh that alone
// lights the receivers unoccluded, each build also against its exact value.
void check_as_triangles(const std::function<void(Scene&)>& build,
                        const std::vector<Shading>& receivers, std::uint64_t seed,
                        std::uint32_t exact_mesh = ~0u) {
    Scene mesh, triangles;
    build(mesh);
    build(triangles);
    triangles.set_mesh_lights(false);
    mesh.commit();
    triangles.commit();
    REQUIRE(count_of(mesh, LightType::Mesh) == 1);
    REQUIRE(count_of(triangles, LightType::Mesh) == 0);
    double z_sum = 0;
    int comparisons = 0;
    for (const Config& c : configs())
        for (const Shading& r : receivers) {
            const testing::PointCopies a = testing::light_point_copies(
                mesh, r.x, r.n, settings_for(mesh, c, seed++), kCopies);
            const testing::PointCopies b = testing::light_point_copies(
                triangles, r.x, r.n, settings_for(triangles, c, seed++), kCopies);
            const double sd = std::sqrt(a.standard_error * a.standard_error +
                                        b.standard_error * b.standard_error);
            INFO(r.what << "; mesh light: " << describe(mesh, c) << "; triangles: "
                        << describe(triangles, c));
            INFO("mesh light " << a.mean << " ± " << a.standard_error << ", triangles "
                               << b.mean << " ± " << b.standard_error);
            CHECK(a.finite);
            CHECK(b.finite);
            // Where every sample sees the same (from inside the sphere, all
            // of it) an estimate is exact but for its sums' rounding.
            const double rounding = 1e-12 * std::max(std::abs(a.mean), std::abs(b.mean));
            CHECK(std::abs(a.mean - b.mean) <= kSigmas * sd + rounding);
            if (exact_mesh != ~0u) {
                const double exact = convex_mesh_exact(triangles, exact_mesh, r.x, r.n);
                INFO("exact " << exact);
                CHECK(std::abs(a.mean - exact) <= kSigmas * a.standard_error + 1e-12 * exact);
                CHECK(std::abs(b.mean - exact) <= kSigmas * b.standard_error + 1e-12 * exact);
            }
            if (sd > rounding) {
                z_sum += (a.mean - b.mean) / sd;
                ++comparisons;
            }
        }
    REQUIRE(comparisons > 0);
    INFO("Σz/√M over " << comparisons << " comparisons: " << z_sum / std::sqrt(comparisons));
    CHECK(std::abs(z_sum) / std::sqrt(double(comparisons)) <= kAggregateSigmas);
}

// The floor under everything: a 60 m square at z = 0, not emissive.
void add_floor(Scene& scene) {
    scene.add_mesh(std::vector<Vec3>{{-30, -30, 0}, {30, -30, 0}, {30, 30, 0}, {-30, 30, 0}},
                   {{0, 1, 2}, {0, 2, 3}});
}

// A point between a face of a 12 × 24 UV sphere (centre c, radius r) and its
// bounding sphere: outside the mesh, inside the sphere. Its face spans θ
// 90°–105°, φ 0–15°; its plane lies ~0.983 r from the centre at its middle.
Vec3 between_face_and_sphere(const Vec3& c, double r) {
    const double theta = kPi * 97.5 / 180, phi = kPi * 7.5 / 180;
    return c + 0.995 * r *
                   Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                        std::cos(theta));
}

// A 12 × 24 UV sphere of radiance 2 over the floor, alone: the two builds
// against each other and each against the exact value (its mesh is mesh 0).
void check_sphere_over_floor(const Vec3& c, double r, const std::vector<Shading>& receivers,
                             std::uint64_t seed) {
    check_as_triangles(
        [&](Scene& s) {
            add_emissive_sphere(s, c, r, 12, 24, Vec3(2, 2, 2));
            add_floor(s);
        },
        receivers, seed, 0);
}

// Whether that sphere's mesh light draws the cosine hemisphere at x.
bool draws_cosine(const Vec3& c, double r, const Vec3& x) {
    Scene probe;
    add_emissive_sphere(probe, c, r, 12, 24);
    probe.commit();
    return !mesh_light_draws_cone(probe.lights()[0], x);
}

}  // namespace

TEST_CASE("mesh lights light as their triangles: a sphere over a floor",
          "[direct][mesh_lights]") {
    const Vec3 c(0, 0, 1);
    const double r = 0.4;
    const std::vector<Shading> receivers = {
        {"under it", {0, 0, 0}, kUp},
        {"under its edge", {0.3, 0.2, 0}, kUp},
        {"beside it", {0.8, -0.3, 0}, kUp},
        {"1.5 m away", {1.5, 0, 0}, kUp},
        {"3 m away", {3, 1, 0}, kUp},
        {"6 m away", {6, 0, 0}, kUp},
        {"12 m away, 5° up", {12, -2, 0}, kUp},
        {"8 m away at its height: straddling the horizon", {8, 0, 1}, kUp},
        {"beside it at its height: straddling the horizon", {1.0, 0, 1}, kUp},
        {"close, facing it", {0.5, 0.1, 1.3}, normalize(Vec3(-1, 0, 0.2))},
        {"inside, at its centre", c, normalize(Vec3(0.3, -0.2, 1))},
        {"between a face and the bounding sphere, facing the face",
         between_face_and_sphere(c, r), normalize(c - between_face_and_sphere(c, r))},
        {"between a face and the bounding sphere, edge-on",
         between_face_and_sphere(c, r), normalize(Vec3(0, 0.3, 1))},
    };
    for (int inside : {10, 11, 12}) REQUIRE(draws_cosine(c, r, receivers[inside].x));
    REQUIRE_FALSE(draws_cosine(c, r, receivers[9].x));
    check_sphere_over_floor(c, r, receivers, 1000);
}

TEST_CASE("mesh lights light as their triangles: a sphere resting on the floor",
          "[direct][mesh_lights]") {
    // Its bottom pole touches the floor at the origin; floor points within
    // ~0.0148 r of it lie inside the bounding sphere grown by the cone
    // margin: they draw the cosine hemisphere.
    const double r = 0.4;
    const Vec3 c(0, 0, r);
    const std::vector<Shading> receivers = {
        {"2 mm from the contact", {0.002, 0, 0}, kUp},
        {"4 mm from the contact", {0.003, 0.0025, 0}, kUp},
        {"1 cm from the contact", {0.01, 0, 0}, kUp},
        {"3 cm from the contact", {0.02, -0.022, 0}, kUp},
        {"10 cm from the contact", {0.1, 0, 0}, kUp},
        {"30 cm from the contact", {0.3, 0.1, 0}, kUp},
        {"60 cm from the contact", {0, -0.6, 0}, kUp},
        {"1.3 m from the contact", {1.2, 0.5, 0}, kUp},
        {"3 m from the contact", {-3, 0, 0}, kUp},
        {"10 m from the contact", {10, 0, 0}, kUp},
    };
    REQUIRE(draws_cosine(c, r, receivers[0].x));
    REQUIRE(draws_cosine(c, r, receivers[1].x));
    REQUIRE_FALSE(draws_cosine(c, r, receivers[2].x));
    check_sphere_over_floor(c, r, receivers, 2000);
}

TEST_CASE("mesh lights light as their triangles: a plate shadows part of the floor",
          "[direct][mesh_lights]") {
    // The plate at z = 0.5 over x ≥ 0.1 hides the sphere (z 0.6–1.4, |x| ≤
    // 0.4) from x ≳ 0.8, and part of it nearer.
    const std::vector<Shading> receivers = {
        {"-1 m", {-1, 0, 0}, kUp},
        {"-0.3 m", {-0.3, 0.1, 0}, kUp},
        {"under the centre", {0, 0, 0}, kUp},
        {"under the plate's edge", {0.1, 0.1, 0}, kUp},
        {"0.25 m, partly shadowed", {0.25, 0, 0}, kUp},
        {"0.5 m, mostly shadowed", {0.5, -0.2, 0}, kUp},
        {"1 m, in the shadow", {1, 0, 0}, kUp},
        {"beside the plate", {0.6, 3.5, 0}, kUp},
        {"on the plate", {0.5, 0, 0.5 + 1e-9}, kUp},
        {"under the plate, facing its underside", {0.3, 0, 0.2}, normalize(Vec3(-1, 0, 1))},
    };
    check_as_triangles(
        [&](Scene& s) {
            add_floor(s);
            add_emissive_sphere(s, Vec3(0, 0, 1), 0.4, 12, 24, Vec3(2, 2, 2));
            s.add_mesh(std::vector<Vec3>{{0.1, -3, 0.5}, {3, -3, 0.5}, {3, 3, 0.5}, {0.1, 3, 0.5}},
                       {{0, 1, 2}, {0, 2, 3}});
        },
        receivers, 3000);
}

TEST_CASE("mesh lights light as their triangles: with a lamp behind it and an emissive quad",
          "[direct][mesh_lights]") {
    // A square lamp at 2 m facing down, which the sphere hides in part from
    // the floor under it, and an emissive quad of 2 triangles (per-triangle
    // lights: the samples among emissive triangles take the closest hit
    // first, direct_lighting.cpp integrand_to_blocker).
    const std::vector<Shading> receivers = {
        {"under the sphere", {0, 0, 0}, kUp},
        {"under the sphere and the lamp", {0.2, 0.1, 0}, kUp},
        {"under the lamp's edge", {0.6, 0, 0}, kUp},
        {"beside", {1, 0.5, 0}, kUp},
        {"-0.5 m", {-0.5, 0, 0}, kUp},
        {"under the quad", {-0.8, 0.3, 0}, kUp},
        {"far", {-1.5, -0.5, 0}, kUp},
        {"between the sphere and the lamp", {0.2, 0, 1.5}, kUp},
        {"near the sphere's underside", {0.3, 0, 0.55}, kUp},
        {"2 m away", {2, 0, 0}, kUp},
    };
    check_as_triangles(
        [&](Scene& s) {
            add_floor(s);
            add_emissive_sphere(s, Vec3(0, 0, 1), 0.4, 12, 24, Vec3(2, 2, 2));
            s.add_light(make_rect_light(Vec3(-0.2, -0.4, 2), Vec3(0, 0.8, 0), Vec3(0.8, 0, 0),
                                        Vec3(5, 5, 5), false, kPi));
            s.add_mesh(std::vector<Vec3>{{-0.9, 0.2, 0.8}, {-0.7, 0.2, 0.8}, {-0.7, 0.4, 0.8},
                                         {-0.9, 0.4, 0.8}},
                       {{0, 1, 2}, {0, 2, 3}}, Vec3(4, 4, 4));
        },
        receivers, 4000);
}

// Why mesh lights exist: a sphere-like mesh seen from afar, drawn through
// its bounding sphere's cone, is seen along nearly every direction drawn
// (the mesh fills ~99 % of the cone); drawn as triangles, half the draws go
// to its far side, hidden, and the rest by per-triangle densities that the
// closest hit and the overlapping triangles make uneven. The relative
// variance of one sample, measured from 4096 one-sample copies: at a floor
// point 1 m below a 16 × 32 UV sphere of radius 0.3 it was 0.011–0.016 with
// the mesh light against 0.23 (the plan's tree/solid-angle) and 0.31
// (power/solid-angle) with its triangles, 14–28× over three seeds. The bound
// asks for 5×, a margin of ~3× for the spread of the variance estimates (the
// per-triangle samples are heavy-tailed) and for changes that are not bugs.
TEST_CASE("mesh lights: much less variance than their triangles", "[direct][mesh_lights]") {
    constexpr int kOneSampleCopies = 4096;
    constexpr double kLeastRatio = 5.0;
    Scene mesh, triangles;
    for (Scene* s : {&mesh, &triangles}) {
        add_emissive_sphere(*s, Vec3(0, 0, 1), 0.3, 16, 32, Vec3(2, 2, 2));
        add_floor(*s);
    }
    triangles.set_mesh_lights(false);
    mesh.commit();
    triangles.commit();
    const Vec3 x(0, 0, 0);
    const auto relative_variance = [&](const Scene& scene, const std::vector<std::string>& names,
                                       testing::PointCopies& e) {
        const DirectLightingSettings s = testing::lighting_settings(
            names, std::vector<int>(names.size(), 1), 1, Strategy::Balance, 17);
        e = testing::light_point_copies(scene, x, kUp, s, kOneSampleCopies);
        REQUIRE(e.stats.samples == std::uint64_t(kOneSampleCopies));
        return e.variance / (e.mean * e.mean);
    };
    for (const bool plan : {true, false}) {
        const std::vector<std::string> mesh_names =
            plan ? testing::plan_names(mesh) : std::vector<std::string>{"power/solid-angle"};
        const std::vector<std::string> triangle_names =
            plan ? testing::plan_names(triangles) : mesh_names;
        REQUIRE(mesh_names.size() == 1);
        REQUIRE(triangle_names.size() == 1);
        testing::PointCopies a, b;
        const double va = relative_variance(mesh, mesh_names, a);
        const double vb = relative_variance(triangles, triangle_names, b);
        INFO(mesh_names[0] << " (mesh light): " << a.mean << " ± " << a.standard_error
                           << ", relative variance a sample " << va << "; " << triangle_names[0]
                           << " (triangles): " << b.mean << " ± " << b.standard_error << ", "
                           << vb);
        CHECK(a.finite);
        CHECK(b.finite);
        // The same value (as the tests above, 5σ)...
        CHECK(std::abs(a.mean - b.mean) <=
              kSigmas * std::sqrt(a.standard_error * a.standard_error +
                                  b.standard_error * b.standard_error));
        // ... at a fraction of the variance.
        CHECK(vb >= kLeastRatio * va);
    }
}

// A bake's texels: each sample draws its own position in the texel's
// footprint, and the cone or the cosine hemisphere there; a texel's later
// passes continue its sequences and reuse its tables; shadowed_draws probes
// the footprint's centre first. The same comparison as above (5σ, the
// copies' standard errors), with T texels (one stream each) of one footprint
// as T independent estimates, over two passes of 8 and 24 rounds.
namespace {

testing::MeanAndError footprint_copies(const Scene& scene, const DirectLightingSettings& settings,
                      const testing::SquareFootprint& footprint, int copies) {
    LightingContext context(scene, settings);
    PointLighting shader(context);
    std::vector<double> v;
    for (int c = 0; c < copies; ++c) {
        double first[3], second[3];
        shader.shade(std::uint64_t(c), 0, 8, footprint.centre(), &footprint, first, nullptr);
        shader.shade(std::uint64_t(c), 8, 24, footprint.centre(), &footprint, second, nullptr);
        v.push_back((8 * first[1] + 24 * second[1]) / 32);
    }
    return testing::mean_and_error(v);
}

}  // namespace

TEST_CASE("mesh lights light as their triangles: texel footprints over passes",
          "[direct][mesh_lights]") {
    constexpr int kTexels = 512;
    struct Case {
        const char* what;
        bool plate;  // the plate of the shadowed scene, over the resting sphere
        testing::SquareFootprint footprint;
    };
    // The resting sphere (r 0.4 about (0, 0, 0.4)); the cone's margin ends
    // ~6 mm from the contact, inside the first footprint. The plate at
    // z = 0.85 over x ≥ 0.3 hides part of the sphere from the third.
    const Case cases[] = {
        {"1 cm texel across the cosine hemisphere's edge", false,
         testing::SquareFootprint(Vec3(0.006, 0.001, 0), 0.005)},
        {"10 cm texel beside the contact", false,
         testing::SquareFootprint(Vec3(0.15, -0.05, 0), 0.05)},
        {"20 cm texel in the plate's penumbra", true,
         testing::SquareFootprint(Vec3(0.8, 0, 0), 0.1)},
    };
    std::uint64_t seed = 5000;
    for (const Case& c : cases) {
        Scene mesh, triangles;
        for (Scene* s : {&mesh, &triangles}) {
            add_floor(*s);
            add_emissive_sphere(*s, Vec3(0, 0, 0.4), 0.4, 12, 24, Vec3(2, 2, 2));
            if (c.plate)
                s->add_mesh(std::vector<Vec3>{{0.3, -3, 0.85}, {3, -3, 0.85}, {3, 3, 0.85},
                                              {0.3, 3, 0.85}},
                            {{0, 1, 2}, {0, 2, 3}});
        }
        triangles.set_mesh_lights(false);
        mesh.commit();
        triangles.commit();
        for (const auto& names : {std::vector<std::string>{"power/solid-angle", "bsdf"},
                                  std::vector<std::string>{"tree/solid-angle"}})
            for (int shadowed_draws : {1, 4}) {
                DirectLightingSettings s = testing::lighting_settings(
                    names, std::vector<int>(names.size(), 2), 1, Strategy::Balance, 0);
                s.shadowed_draws = shadowed_draws;
                s.seed = seed++;
                const testing::MeanAndError a = footprint_copies(mesh, s, c.footprint, kTexels);
                s.seed = seed++;
                const testing::MeanAndError b = footprint_copies(triangles, s, c.footprint, kTexels);
                INFO(c.what << ", " << names.front() << " and " << names.size() - 1
                            << " more, shadowed_draws " << shadowed_draws << ": mesh light "
                            << a.mean << " ± " << a.standard_error << ", triangles " << b.mean
                            << " ± " << b.standard_error);
                CHECK(std::isfinite(a.mean));
                CHECK(std::isfinite(b.mean));
                CHECK(b.standard_error > 0);
                CHECK(std::abs(a.mean - b.mean) <=
                      kSigmas * std::sqrt(a.standard_error * a.standard_error +
                                          b.standard_error * b.standard_error));
            }
    }
}

// shadowed_draws' probe (direct_lighting.cpp, centre_in_shadow) weighs and
// traces each light's middle point: a mesh light's is its cone's axis (the
// cosine's normal inside its sphere), seen where the closest hit is on its
// mesh. Two emissive spheres over the floor, drawn uniformly with the probe
// on: a texel between them that sees both is drawn
// once a count, one under a plate that hides both four times.
TEST_CASE("mesh lights: shadowed_draws' probe sees them", "[direct][mesh_lights]") {
    for (bool plate : {false, true}) {
        Scene scene;
        add_emissive_sphere(scene, Vec3(0, 0, 1), 0.3, 16, 32, Vec3(2, 2, 2));
        add_emissive_sphere(scene, Vec3(1, 0, 1), 0.3, 16, 32, Vec3(2, 2, 2));
        add_floor(scene);
        if (plate)
            scene.add_mesh(std::vector<Vec3>{{-0.5, -0.5, 0.3}, {1.5, -0.5, 0.3},
                                             {1.5, 0.5, 0.3}, {-0.5, 0.5, 0.3}},
                           {{0, 1, 2}, {0, 2, 3}});
        scene.commit();
        REQUIRE(count_of(scene, LightType::Mesh) == 2);
        // Uniform selection with the probe on, as the plan takes for lamps of
        // comparable power (mesh lights take `defensive` there: effect_plan.cpp).
        DirectLightingSettings s;
        s.techniques = {*parse_technique("uniform/solid-angle")};
        s.samples = {1};
        s.shadowed_draws = kShadowedDraws;
        LightingContext context(scene, s);
        PointLighting shader(context);
        const testing::SquareFootprint texel(Vec3(0.5, 0, 0), 0.05);
        double value[3];
        shader.shade(0, 0, 4, texel.centre(), &texel, value, nullptr);
        INFO((plate ? "under the plate" : "in the open") << ": " << value[1]);
        CHECK(shader.draws_per_count() == (plate ? kShadowedDraws : 1));
        if (plate)
            CHECK(value[1] == 0);
        else
            CHECK(value[1] > 0);
    }
}

// A world among emitters (effect_plan.cpp, world_seen_through_emitters): it
// is seen through the emitters by `bsdf` only where every emitter is at least
// as bright as the world (else the emitters' part L_e − L_w would be
// negative); a mesh light is such an emitter as its triangles are. A minor
// world (the plan's world_by_bsdf) among few lights: the sphere as a mesh
// light, a bright emissive quad (two triangle lights) and an opaque box.
namespace {

void build_world_scene(Scene& scene, double sphere_radiance, bool quad = true) {
    add_emissive_sphere(scene, Vec3(0, 0, 1), 0.4, 12, 24, Vec3(1, 1, 1) * sphere_radiance);
    if (quad)
        scene.add_mesh(std::vector<Vec3>{{0.6, -0.2, 0.9}, {1.0, -0.2, 0.9}, {1.0, 0.2, 0.9},
                                         {0.6, 0.2, 0.9}},
                       {{0, 1, 2}, {0, 2, 3}}, Vec3(6, 6, 6));
    add_box(scene, Vec3(-1.2, -0.2, 0.3), Vec3(-0.8, 0.2, 0.6), std::nullopt);
    scene.add_light(make_world_light(Vec3(0.1, 0.1, 0.1)));
}

}  // namespace

TEST_CASE("mesh lights: the world is seen through them only where they outshine it",
          "[direct][mesh_lights][world]") {
    struct Case {
        double sphere_radiance;
        bool quad;
    };
    for (const Case c : {Case{0.05, true}, Case{3.0, true}, Case{3.0, false}}) {
        INFO("sphere radiance " << c.sphere_radiance << ", world 0.1"
                                << (c.quad ? ", a quad" : ""));
        Scene scene;
        build_world_scene(scene, c.sphere_radiance, c.quad);
        scene.commit();
        REQUIRE(count_of(scene, LightType::Mesh) == 1);
        std::vector<Technique> techniques;
        std::vector<int> samples;
        default_techniques(scene, techniques, samples);
        const EffectPlan plan = plan_effects(scene, techniques, samples);
        REQUIRE(plan.world_by_bsdf);
        CHECK(plan.world_through_emitters == (c.sphere_radiance >= 0.1));
    }
}

// The world seen through a mesh light (its part by `bsdf` wherever no opaque
// surface is hit first, the mesh's L_e − L_w by the light techniques) or
// behind a dim one: unbiased as with its triangles (whose plan, among many
// lights, does not see the world through them).
TEST_CASE("mesh lights light as their triangles: with a world", "[direct][mesh_lights][world]") {
    const std::vector<Shading> receivers = {
        {"under the sphere", {0, 0, 0}, kUp},
        {"under the quad", {0.8, 0, 0.3}, kUp},
        {"beside the box", {-0.6, 0.1, 0.2}, kUp},
        {"under the box", {-1, 0, 0.1}, kUp},
        {"near the sphere's underside", {0.3, 0.2, 0.55}, kUp},
        {"inside the sphere", {0, 0, 1}, normalize(Vec3(0.2, 0, 1))},
        {"beside the sphere, facing it", {0.6, 0, 1}, Vec3(-1, 0, 0)},
        {"2 m away", {2, 0, 0}, kUp},
    };
    std::uint64_t seed = 6000;
    for (double sphere_radiance : {0.05, 3.0})
        for (bool quad : {true, false}) {
            INFO("sphere radiance " << sphere_radiance << ", world 0.1"
                                    << (quad ? ", a quad" : ""));
            check_as_triangles(
                [&](Scene& s) { build_world_scene(s, sphere_radiance, quad); }, receivers, seed);
            seed += 1000;
        }
}
