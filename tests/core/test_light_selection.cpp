// Light selection (render/light_selection.h) and direct lighting through it
// with many lights (SPEC §3, §5).
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "math/random.h"
#include "render/direct_lighting.h"
#include "render/light_selection.h"
#include "sampling/irradiance.h"
#include "sampler_check.h"
#include "support/lighting_settings.h"

using namespace omis;

namespace {

// A mixed set: rects facing down and up, an ellipse, two-sided triangles,
// sphere and delta point lights, a spot, a sun and a world.
std::vector<Light> mixed_lights() {
    std::vector<Light> lights;
    const Vec3 white(1, 1, 1);
    for (int i = 0; i < 12; ++i) {
        const double x = -3 + 0.5 * i;
        const bool down = i % 3 != 0;
        lights.push_back(make_rect_light(Vec3(x, -0.2, 1 + 0.1 * i), Vec3(0, 0.4, 0),
                                         Vec3(down ? 0.3 : -0.3, 0, 0), white * (1 + i),
                                         false, kPi));
    }
    lights.push_back(make_ellipse_light(Vec3(0, 2, 1), Vec3(0.3, 0, 0), Vec3(0, -0.2, 0),
                                        white * 5, false, 1.0));
    for (int i = 0; i < 8; ++i)
        lights.push_back(make_triangle_light(Vec3(i, 0, 2), Vec3(i + 0.2, 0, 2),
                                             Vec3(i, 0.2, 2.1), white * 3, true));
    lights.push_back(make_point_light(Vec3(1, 1, 1), white * 10, 0.1));
    lights.push_back(make_point_light(Vec3(-1, 1, -1), white * 10, 0));
    lights.push_back(make_spot_light(Vec3(0, 0, 3), Vec3(0, 0, -1), white * 20, 0, 0.8, 0.2));
    lights.push_back(make_sun_light(Vec3(0, 0.3, -1), white, 0.1));
    lights.push_back(make_world_light(white * 0.1));
    return lights;
}

std::vector<std::uint32_t> all_ids(std::size_t n) {
    std::vector<std::uint32_t> ids(n);
    for (std::size_t i = 0; i < n; ++i) ids[i] = std::uint32_t(i);
    return ids;
}

const LightSelector::Kind kKinds[] = {LightSelector::Kind::Uniform, LightSelector::Kind::Power,
                                      LightSelector::Kind::Tree};

}  // namespace

TEST_CASE("selection pmfs sum to 1 and match drawing frequencies", "[selection]") {
    const std::vector<Light> lights = mixed_lights();
    const std::vector<std::uint32_t> ids = all_ids(lights.size());
    const std::vector<std::pair<Vec3, Vec3>> points = {
        {Vec3(0, 0, 0), Vec3(0, 0, 1)},
        {Vec3(2, 0.5, 1.5), normalize(Vec3(1, 0, 1))},
        {Vec3(0.1, 0.1, 2.05), Vec3(0, 0, -1)},  // among the triangles
    };
    for (auto kind : kKinds) {
        const LightSelector s(kind, lights, ids, 10.0);
        for (const auto& [x, n] : points) {
            INFO("kind " << int(kind) << " x " << x.x << "," << x.y << "," << x.z);
            std::vector<double> pmf(lights.size());
            double total = 0;
            for (std::uint32_t l : ids) total += pmf[l] = s.pmf(x, n, l);
            // Every draw ends at a light (the tree splits by power where its
            // bounds reach a node but neither child): exactly 1 but round-off.
            CHECK(total == Approx(1.0).epsilon(1e-12));

            // Pearson's chi-square of N draws against the pmfs (lights expected
            // < 5 times pooled), at the shared checker's significance kAlpha.
            const int N = 100000;
            std::vector<double> count(lights.size());
            double none = 0;
            Pcg32 rng(7, 11);
            for (int i = 0; i < N; ++i) {
                const auto pick = s.sample(x, n, rng.next_double());
                if (!pick) {
                    none += 1;
                    continue;
                }
                REQUIRE(pick->pmf == Approx(pmf[pick->light]).epsilon(1e-12));
                count[pick->light] += 1;
            }
            std::vector<double> observed, expected;
            for (std::uint32_t l : ids) {
                observed.push_back(count[l]);
                expected.push_back(N * pmf[l]);
                if (pmf[l] == 0) CHECK(count[l] == 0);
            }
            CHECK(none == 0);
            CHECK(testing::chi_square_pvalue(observed, expected) > testing::kAlpha);
        }
    }
}

TEST_CASE("a selection's rest is uniform in the unit interval and independent of the light chosen",
          "[selection]") {
    // The shape draw takes SelectedLight::rest as a coordinate: given the
    // light, it must be uniform. Pearson's chi-square over (light, quarter of
    // [0, 1) the rest falls in) against N · pmf / 4 (pooled below 5), at the
    // shared checker's significance kAlpha.
    const std::vector<Light> lights = mixed_lights();
    const std::vector<std::uint32_t> ids = all_ids(lights.size());
    const Vec3 x(2, 0.5, 1.5), n = normalize(Vec3(1, 0, 1));
    constexpr int kQuarters = 4;
    for (auto kind : kKinds) {
        INFO("kind " << int(kind));
        const LightSelector s(kind, lights, ids, 10.0);
        const int N = 200000;
        std::vector<double> count(lights.size() * kQuarters);
        Pcg32 rng(5, 3);
        for (int i = 0; i < N; ++i) {
            const auto pick = s.sample(x, n, rng.next_double());
            REQUIRE(pick);
            REQUIRE(pick->rest >= 0.0);
            REQUIRE(pick->rest < 1.0);
            count[pick->light * kQuarters + int(pick->rest * kQuarters)] += 1;
        }
        std::vector<double> observed, expected;
        for (std::uint32_t l : ids)
            for (int q = 0; q < kQuarters; ++q) {
                observed.push_back(count[l * kQuarters + q]);
                expected.push_back(N * s.pmf(x, n, l) / kQuarters);
            }
        CHECK(testing::chi_square_pvalue(observed, expected) > testing::kAlpha);
    }
}

namespace {

// Does the light send anything to (x, n)? For delta lights exactly; for the
// others, whether one of 256 directions sampled toward the light (by area, so
// spread and one-sidedness are judged per emitting point) carries radiance
// above the horizon.
bool reaches(const Light& light, const Vec3& x, const Vec3& n) {
    if (light.is_delta()) return delta_illumination(light, x, n).has_value();
    if (!light_reaches(light, x, n)) return false;
    for (int i = 0; i < 16; ++i)
        for (int j = 0; j < 16; ++j) {
            const auto s = sample_light(light, ShapeSampler::Area, x, n, (i + 0.5) / 16,
                                        (j + 0.5) / 16);
            if (!s || dot(s->dir, n) <= 0) continue;
            const auto e = emitted_radiance(light, x, s->dir);
            if (e && luminance(e->radiance) > 0) return true;
        }
    return false;
}

}  // namespace

TEST_CASE("the light tree never leaves out a light that reaches the point", "[selection]") {
    const std::vector<Light> lights = mixed_lights();
    const LightSelector s(LightSelector::Kind::Tree, lights, all_ids(lights.size()), 10.0);
    Pcg32 rng(3, 5);
    for (int i = 0; i < 200; ++i) {
        const Vec3 x(rng.next_double() * 8 - 4, rng.next_double() * 4 - 2,
                     rng.next_double() * 4 - 1);
        const Vec3 n = normalize(Vec3(rng.next_double() - 0.5, rng.next_double() - 0.5,
                                      rng.next_double() - 0.5));
        for (std::uint32_t l = 0; l < lights.size(); ++l) {
            const Light& light = lights[l];
            if (reaches(light, x, n)) {
                INFO("light " << l << " x " << x.x << "," << x.y << "," << x.z);
                CHECK(s.pmf(x, n, l) > 0);
            }
        }
    }
}

namespace {

// Many lights over a receiver at the origin facing up, nothing occluding them:
// an emissive grid mesh (3200 triangles) at z = 2, 100 small rects at z = 1
// facing down, 100 delta point lights at z = 1.5 (sampled by the tree, as
// more than kManyDeltaLights). The exact E/π is the sum of closed forms.
struct ManyLights {
    Scene scene;
    double exact = 0;  // at the origin, normal +z (green channel)

    ManyLights() {
        const Vec3 o(0, 0, 0), up(0, 0, 1);
        const int g = 40;
        std::vector<Vec3> positions;
        std::vector<std::array<std::uint32_t, 3>> triangles;
        for (int j = 0; j <= g; ++j)
            for (int i = 0; i <= g; ++i)
                positions.push_back(Vec3(-1 + 2.0 * i / g, -1 + 2.0 * j / g, 2));
        for (int j = 0; j < g; ++j)
            for (int i = 0; i < g; ++i) {
                const std::uint32_t a = j * (g + 1) + i;
                triangles.push_back({a, a + 1, a + g + 2});
                triangles.push_back({a, a + g + 2, a + g + 1});
            }
        const double mesh_radiance = 0.5;
        scene.add_mesh(positions, triangles, Vec3(1, 1, 1) * mesh_radiance);
        exact += mesh_radiance *
                 polygon_irradiance(o, up, {{-1, -1, 2}, {1, -1, 2}, {1, 1, 2}, {-1, 1, 2}});
        for (int j = 0; j < 10; ++j)
            for (int i = 0; i < 10; ++i) {
                const Vec3 corner(-3 + 0.6 * i, -3 + 0.6 * j, 1);
                const Vec3 eu(0, 0.1, 0), ev(0.1, 0, 0);  // emits toward −z
                const double radiance = 2 + (i + j) % 5;
                scene.add_light(make_rect_light(corner, eu, ev, Vec3(1, 1, 1) * radiance,
                                                false, kPi));
                exact += radiance * polygon_irradiance(o, up, {corner, corner + eu,
                                                               corner + eu + ev, corner + ev});
            }
        for (int j = 0; j < 10; ++j)
            for (int i = 0; i < 10; ++i) {
                const Vec3 p(-4 + 0.8 * i, -4 + 0.8 * j, 1.5);
                const double intensity = 0.05;
                scene.add_light(make_point_light(p, Vec3(1, 1, 1) * intensity, 0));
                exact += intensity * p.z / std::pow(length(p), 3);
            }
        exact /= kPi;
        scene.commit();
    }
};

}  // namespace

TEST_CASE("direct lighting through the light tree matches the exact answer with many lights",
          "[selection][direct]") {
    ManyLights m;
    const int copies = 64;
    for (Strategy strategy : {Strategy::Balance, Strategy::OptimalDirect}) {
        DirectLightingSettings s;
        for (const char* name : {"tree/solid-angle", "power/area", "bsdf"})
            s.techniques.push_back(*parse_technique(name));
        s.samples = {4, 2, 2};
        s.rounds = 2;
        s.strategy = strategy;
        s.seed = 5;
        std::vector<double> points(3 * copies, 0.0), normals, value(3 * copies),
            variance(3 * copies);
        for (int i = 0; i < copies; ++i) normals.insert(normals.end(), {0.0, 0.0, 1.0});
        const DirectLightingStats stats = direct_lighting(
            m.scene, points.data(), normals.data(), copies, s, value.data(), variance.data());
        CHECK(stats.plan.sample_delta_lights);
        CHECK(stats.plan.to_string().find("light tree") != std::string::npos);
        // Independent copies (own streams): their mean lies within 4 standard
        // errors, measured from the copies, of the exact value (miss 6e-5).
        double mean = 0, var = 0;
        for (int i = 0; i < copies; ++i) mean += value[3 * i + 1] / copies;
        for (int i = 0; i < copies; ++i)
            var += (value[3 * i + 1] - mean) * (value[3 * i + 1] - mean) / (copies - 1);
        const double standard_error = std::sqrt(var / copies);
        INFO("strategy " << int(strategy) << " mean " << mean << " ± " << standard_error
                         << " exact " << m.exact);
        CHECK(standard_error > 0);
        CHECK(std::abs(mean - m.exact) <= 4 * standard_error);
    }
}

TEST_CASE("the plan picks the light tree by default for many emitters", "[selection]") {
    ManyLights m;
    std::vector<Technique> techniques;
    std::vector<int> samples;
    default_techniques(m.scene, techniques, samples);
    REQUIRE(!techniques.empty());
    CHECK(techniques[0].name() == "tree/solid-angle");
    CHECK(parse_technique("tree/area")->selection == SelectionRule::Tree);
}

namespace {

using testing::plan_names;

// An emissive grid of g × g quads (2 triangles each) of side `size` at height z.
void add_emissive_grid(Scene& scene, int g, double size, double z) {
    std::vector<Vec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    for (int j = 0; j <= g; ++j)
        for (int i = 0; i <= g; ++i)
            positions.push_back(Vec3(size * (double(i) / g - 0.5), size * (double(j) / g - 0.5), z));
    for (int j = 0; j < g; ++j)
        for (int i = 0; i < g; ++i) {
            const std::uint32_t a = std::uint32_t(j * (g + 1) + i);
            triangles.push_back({a, a + 1, a + std::uint32_t(g) + 2});
            triangles.push_back({a, a + std::uint32_t(g) + 2, a + std::uint32_t(g) + 1});
        }
    scene.add_mesh(positions, triangles, Vec3(1, 1, 1));
}

}  // namespace

// Many emitters: one technique (one sequence of N samples beats three of N/3;
// effect_plan.cpp has the measurements), cosine sampling beside it only where
// emitters cover much of the hemisphere.
TEST_CASE("among many emitters the plan draws from the light tree alone, with bsdf for a "
          "world or a huge emissive mesh",
          "[selection]") {
    ManyLights many;  // a 2 m panel under 100 rects spread over 6 m: nothing huge
    CHECK(plan_names(many.scene) == std::vector<std::string>{"tree/solid-angle"});

    Scene small_panel;  // 0.5 m of 128 triangles over a 2 m floor
    add_emissive_grid(small_panel, 8, 0.5, 1.0);
    small_panel.add_mesh({{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}}, {{0, 1, 2}, {0, 2, 3}});
    small_panel.commit();
    CHECK(plan_names(small_panel) == std::vector<std::string>{"tree/solid-angle"});

    // The same triangles, each small, make a 4 m panel over the floor: huge.
    Scene huge_panel;
    add_emissive_grid(huge_panel, 8, 4.0, 0.3);
    huge_panel.add_mesh({{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}}, {{0, 1, 2}, {0, 2, 3}});
    huge_panel.commit();
    CHECK(plan_names(huge_panel) == std::vector<std::string>{"tree/solid-angle", "bsdf"});

    Scene with_world;
    add_emissive_grid(with_world, 8, 0.5, 1.0);
    with_world.add_light(make_world_light(Vec3(1, 1, 1) * 0.2));
    with_world.commit();
    CHECK(plan_names(with_world) == std::vector<std::string>{"tree/solid-angle", "bsdf"});
}

// Two lights that give x the same irradiance, placed symmetrically about its
// normal, must be drawn about equally often whatever their kinds: the tree
// weighs its bounds by irradiance, not by flux (a two-sided light's flux
// counts a side x cannot see; a point light's is 4π I against π I).
TEST_CASE("the light tree weighs lights of different kinds by the irradiance they give",
          "[selection]") {
    const Vec3 x(0, 0, 0), n(0, 0, 1);
    const double s = 0.001, r = 1 / std::sqrt(2.0);  // 1 mm lights, 1.4 m away
    const Vec3 radiance(2, 2, 2);
    // Facing x from (1, 0, 1): cross(edge_u, edge_v) points toward x.
    auto right = [&](bool two_sided) {
        const Vec3 eu(0, s, 0), ev(s * r, 0, -s * r);
        return make_rect_light(Vec3(1, 0, 1) - (eu + ev) * 0.5, eu, ev, radiance, two_sided, kPi);
    };
    // The same from (−1, 0, 1).
    auto left = [&](bool two_sided) {
        const Vec3 eu(-s * r, 0, -s * r), ev(0, s, 0);
        return make_rect_light(Vec3(-1, 0, 1) - (eu + ev) * 0.5, eu, ev, radiance, two_sided, kPi);
    };
    // A sphere light of intensity L·A: at this distance its irradiance is the rect's.
    const Light point = make_point_light(Vec3(-1, 0, 1), radiance * (s * s), 1e-5);
    const std::vector<std::pair<Light, Light>> pairs = {
        {right(false), left(false)}, {right(false), left(true)}, {right(true), left(false)},
        {right(false), point}};
    for (const auto& [a, b] : pairs) {
        const std::vector<Light> lights = {a, b};
        const LightSelector tree(LightSelector::Kind::Tree, lights, all_ids(2), 10.0);
        const double pa = tree.pmf(x, n, 0), pb = tree.pmf(x, n, 1);
        INFO("two-sided " << a.two_sided << ", " << b.two_sided << "; point " << (b.type == LightType::Point));
        CHECK(pa + pb == Approx(1.0));
        // The bounds of a 1 mm light seen from 1.4 m subtend θb < 1e-3 rad:
        // each cosine bound exceeds the exact cosine (45°) by a factor
        // < 1 + θb·tan 45°, so the pmfs differ from 1/2 by < 1e-3 relative.
        // (Weighed by flux, the two-sided pair gave 1/3 and 2/3, the point 1/5.)
        CHECK(pa == Approx(0.5).epsilon(1e-3));
    }
}

TEST_CASE("the emitter shapes find every area light a direction crosses", "[selection]") {
    // Rects, ellipses (both facing ways) and an emissive mesh around x: every
    // light whose exact shape a random direction crosses must be among the
    // candidates Embree returns (extra candidates are allowed: callers check).
    Scene scene;
    std::vector<Vec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    for (int i = 0; i < 12; ++i) {
        const double a = 2 * kPi * i / 12;
        const Vec3 c(2 * std::cos(a), 2 * std::sin(a), 0.3 * (i % 3) - 0.3);
        const Vec3 u = Vec3(-std::sin(a), std::cos(a), 0) * 0.7, v(0, 0, 0.5 + 0.05 * i);
        if (i % 2)
            scene.add_light(make_rect_light(c, i % 4 == 1 ? u : v, i % 4 == 1 ? v : u,
                                            Vec3(1, 1, 1), false, kPi));
        else
            scene.add_light(make_ellipse_light(c, u, v, Vec3(1, 1, 1), i % 4 == 0, kPi));
        const std::uint32_t base = std::uint32_t(positions.size());
        positions.insert(positions.end(), {c * 1.5, c * 1.5 + u, c * 1.5 + v});
        triangles.push_back({base, base + 1, base + 2});
    }
    scene.add_mesh(positions, triangles, Vec3(1, 1, 1));
    scene.commit();
    const Vec3 x(0.1, -0.05, 0.02);
    Pcg32 rng(13, 17);
    int crossings = 0;
    std::vector<std::uint32_t> along;
    for (int i = 0; i < 20000; ++i) {
        const double z = 2 * rng.next_double() - 1, phi = 2 * kPi * rng.next_double();
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        const Vec3 w(r * std::cos(phi), r * std::sin(phi), z);
        along.clear();
        scene.emitter_shapes().lights_along(x, w, along);
        for (std::uint32_t l = 0; l < scene.lights().size(); ++l) {
            if (!emitted_radiance(scene.lights()[l], x, w)) continue;
            ++crossings;
            INFO("light " << l << " direction " << w.x << "," << w.y << "," << w.z);
            CHECK(std::find(along.begin(), along.end(), l) != along.end());
        }
    }
    CHECK(crossings > 1000);  // the check saw many crossings
}
