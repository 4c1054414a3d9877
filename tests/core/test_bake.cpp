// Baking: UV coverage, margin, agreement with Lambert per texel, determinism,
// budgets, cancel and bad input.
#include <catch2/catch.hpp>

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <random>

#include "bake/bake.h"
#include "bake/vertex_points.h"
#include "bake/uv_raster.h"
#include "sampling/irradiance.h"
#include "support/floor_lambert.h"
#include "support/unit_square.h"

using namespace omis;

namespace {

// A grid of (n × n) quads over [0,1]² in both position (z = 0) and UV, each
// split along a diagonal chosen at random; interior vertices jittered so edges
// are not axis aligned. Diagonals of unjittered cells pass exactly through
// texel centres, which exercises the tie rule.
MeshInput grid_mesh(int n, double jitter, std::uint32_t seed, std::vector<float>& positions,
                    std::vector<std::uint32_t>& triangles, std::vector<float>& uvs) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-jitter, jitter);
    positions.clear();
    triangles.clear();
    uvs.clear();
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            double x = double(i) / n, y = double(j) / n;
            if (i > 0 && i < n && j > 0 && j < n) {
                x += u(rng) / n;
                y += u(rng) / n;
            }
            positions.insert(positions.end(), {float(x), float(y), 0.f});
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            if (rng() & 1)
                triangles.insert(triangles.end(), {a, b, d, a, d, c});
            else
                triangles.insert(triangles.end(), {a, b, c, b, d, c});
        }
    for (std::uint32_t idx : triangles) uvs.insert(uvs.end(), {positions[3 * idx], positions[3 * idx + 1]});
    MeshInput m;
    m.name = "grid";
    m.positions = ScalarArray::of(positions.data(), positions.size() / 3, 3);
    m.triangles = IndexArray{triangles.data(), triangles.size() / 3, 3};
    m.uvs = ScalarArray::of(uvs.data(), uvs.size() / 2, 2);
    return m;
}

struct Floor {
    std::vector<float> positions, uvs;
    std::vector<std::uint32_t> triangles;
};

// A 2 m floor (z = 0) under a 1 m rect light at height 1 facing down.
void floor_scene(Scene& scene, Floor& f, int cells = 4) {
    MeshInput m = grid_mesh(cells, 0.0, 1, f.positions, f.triangles, f.uvs);
    for (std::size_t i = 0; i < f.positions.size(); i += 3) {
        f.positions[i] = 2 * f.positions[i] - 1;
        f.positions[i + 1] = 2 * f.positions[i + 1] - 1;
    }
    scene.add_mesh(m);
    scene.add_light(make_rect_light(Vec3(-0.5, -0.5, 1), Vec3(0, 1, 0), Vec3(1, 0, 0),
                                    Vec3(2, 2, 2), false, kPi));
    scene.commit();
}

using testing::floor_lambert;

double lambert_footprint(const Scene& scene, const UvCoverage& cov, std::size_t i) {
    return testing::floor_lambert_footprint(scene, cov, i, 32);
}

BakeSettings floor_settings(int size) {
    BakeSettings s;
    s.lighting.techniques = {*parse_technique("uniform/solid-angle"),
                             *parse_technique("uniform/area")};
    s.lighting.samples = {4, 4};
    s.lighting.rounds = 4;
    s.lighting.strategy = Strategy::Balance;
    s.width = s.height = size;
    return s;
}

}  // namespace

TEST_CASE("coverage: a unit quad covers every texel exactly once", "[bake]") {
    for (auto [w, h] : {std::pair{1, 1}, {7, 5}, {64, 64}, {100, 37}, {513, 129}}) {
        std::vector<float> p, uv;
        std::vector<std::uint32_t> t;
        GeometryScene scene;
        scene.add_mesh(grid_mesh(1, 0, 3, p, t, uv));
        const UvCoverage c = rasterize_uv(scene.mesh(0), w, h);
        INFO(w << "×" << h);
        CHECK(c.covered == std::size_t(w) * h);
        CHECK(c.overlapping_texels == 0);
    }
}

TEST_CASE("coverage: islands with shared edges have no cracks and no double coverage",
          "[bake]") {
    for (std::uint32_t seed : {1u, 2u, 3u}) {
        for (double jitter : {0.0, 0.3}) {
            std::vector<float> p, uv;
            std::vector<std::uint32_t> t;
            GeometryScene scene;
            scene.add_mesh(grid_mesh(9, jitter, seed, p, t, uv));
            for (int size : {16, 45, 128}) {
                const UvCoverage c = rasterize_uv(scene.mesh(0), size, size);
                INFO("seed " << seed << " jitter " << jitter << " size " << size);
                CHECK(c.covered == std::size_t(size) * size);
                CHECK(c.overlapping_texels == 0);
            }
        }
    }
}

TEST_CASE("margin fills exactly the requested ring from the nearest texel", "[bake]") {
    // One island: a quad over UV [0.4, 0.6]², 20×20 texels.
    const auto square = testing::UnitSquare::island(0.4f, 0.6f);
    GeometryScene scene;
    scene.add_mesh(square.input());
    const UvCoverage c = rasterize_uv(scene.mesh(0), 20, 20);
    REQUIRE(c.covered == 16);  // texels 8..11 in x and y
    for (int margin : {0, 1, 3}) {
        const auto src = margin_sources(c, margin);
        for (int y = 0; y < 20; ++y)
            for (int x = 0; x < 20; ++x) {
                const int dx = x < 8 ? 8 - x : (x > 11 ? x - 11 : 0);
                const int dy = y < 8 ? 8 - y : (y > 11 ? y - 11 : 0);
                const int chebyshev = std::max(dx, dy);
                const std::int64_t s = src[y * 20 + x];
                INFO("margin " << margin << " texel " << x << "," << y);
                CHECK((s >= 0) == (chebyshev <= margin));
                if (s >= 0) {
                    // The source is the nearest covered texel: the clamp into the island.
                    CHECK(s % 20 == std::clamp(x, 8, 11));
                    CHECK(s / 20 == std::clamp(y, 8, 11));
                }
            }
    }
}

TEST_CASE("lightmap of an unoccluded floor agrees with Lambert per texel", "[bake]") {
    Scene scene;
    Floor f;
    floor_scene(scene, f);
    for (Strategy strategy : {Strategy::Balance, Strategy::OptimalProgressive}) {
        BakeSettings s = floor_settings(48);
        s.lighting.strategy = strategy;
        s.samples = 36;  // 3 rounds of 8 and a final one of 12
        const BakeResult r = bake(scene, s);
        REQUIRE(r.stats.covered == 48u * 48u);
        const UvCoverage cov = rasterize_uv(scene.geometry().mesh(0), 48, 48);
        // Per texel z = (value − exact)/σ̂. In aggregate: the mean error over
        // the image within 4 standard errors of the mean (Σσ̂²/n²), and no
        // more than 1 % of texels beyond 4σ̂ (a normal tail holds 6e-5; the
        // per-texel σ̂ from 32 draws is itself noisy, hence the slack).
        double sum_err = 0, sum_var = 0;
        int beyond = 0, n = 0;
        for (int y = 0; y < 48; ++y)
            for (int x = 0; x < 48; ++x) {
                const int i = y * 48 + x;
                const double err = r.value[3 * i + 1] - lambert_footprint(scene, cov, i);
                const double sd = r.noise[i] * r.value[3 * i + 1];
                CHECK(std::isfinite(r.value[3 * i + 1]));
                sum_err += err;
                sum_var += sd * sd;
                beyond += std::abs(err) > 4 * sd;
                ++n;
            }
        INFO(strategy_name(strategy));
        CHECK(std::abs(sum_err / n) <= 4 * std::sqrt(sum_var) / n);
        CHECK(beyond <= n / 100);
    }
}

TEST_CASE("vertex and corner bakes agree with Lambert", "[bake]") {
    Scene scene;
    Floor f;
    floor_scene(scene, f, 6);
    for (BakeTarget target : {BakeTarget::Vertices, BakeTarget::Corners}) {
        BakeSettings s = floor_settings(0);
        s.target = target;
        s.lighting.rounds = 64;
        const BakeResult r = bake(scene, s);
        const Mesh& mesh = scene.geometry().mesh(0);
        const std::size_t expected = target == BakeTarget::Vertices ? mesh.positions.size()
                                                                    : 3 * mesh.num_triangles();
        REQUIRE(std::size_t(r.width) == expected);
        // Corners sit just inside their triangle, as Cycles places them; a
        // vertex is the mean of its corners (bake/vertex_points.h).
        std::vector<double> exact(expected, 0.0);
        std::vector<int> corners(expected, 0);
        for (std::uint32_t t = 0; t < mesh.num_triangles(); ++t)
            for (int k = 0; k < 3; ++k) {
                const CornerPoint c = inset_corner(mesh, t, k);
                const std::size_t i =
                    target == BakeTarget::Vertices ? mesh.triangles[t][k] : 3 * t + k;
                exact[i] += floor_lambert(mesh.position(t, c.b1, c.b2));
                ++corners[i];
            }
        for (std::size_t i = 0; i < expected; ++i) {
            const double lambert_value = exact[i] / corners[i];
            const double sd = r.noise[i] * r.value[3 * i];
            // 5σ̂ per vertex: ~100 points are checked, so 4σ̂ (6e-5 each) would
            // leave a 0.6 % chance of a false alarm; 5σ̂ leaves 6e-5 in all.
            CHECK(std::abs(r.value[3 * i] - lambert_value) <= 5 * sd + 1e-9);
        }
    }
}

TEST_CASE("the same seed gives the same bits at any thread count", "[bake]") {
    Scene scene;
    Floor f;
    floor_scene(scene, f);
    BakeSettings s = floor_settings(40);
    s.lighting.strategy = Strategy::OptimalDirect;
    BakeResult one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = bake(scene, s);
    }
    const BakeResult all = bake(scene, s);
    CHECK(one.value == all.value);
    CHECK(one.noise == all.noise);
}

TEST_CASE("budgets: time and noise", "[bake]") {
    Scene scene;
    Floor f;
    floor_scene(scene, f);
    SECTION("a time budget ends on whole passes: every texel takes the same count") {
        BakeSettings s = floor_settings(32);
        s.lighting.rounds = 1 << 20;  // effectively unlimited
        s.time_budget = 0.3;
        const BakeResult r = bake(scene, s);
        CHECK(r.stats.status == BakeStatus::TimeBudget);
        CHECK(r.stats.passes >= 1);
        // No wall-clock bound (the machine may be shared; bench/ measures
        // time): the bake's own records show that every pass after the first
        // began before the budget ran out.
        const auto& passes = r.stats.convergence;
        REQUIRE(passes.size() == std::size_t(r.stats.passes));
        for (std::size_t i = 1; i < passes.size(); ++i) CHECK(passes[i - 1].seconds < 0.3);
        const std::uint32_t first = r.samples[0];
        CHECK(first >= 8u);  // at least the first pass (one round of 8)
        for (std::size_t i = 0; i < r.samples.size(); ++i) CHECK(r.samples[i] == first);
        CHECK(r.stats.samples_per_texel == Approx(first));
    }
    SECTION("the first pass always completes, however short the budget") {
        BakeSettings s = floor_settings(32);
        s.lighting.rounds = 1 << 20;
        s.time_budget = 1e-9;
        const BakeResult r = bake(scene, s);
        CHECK(r.stats.status == BakeStatus::TimeBudget);
        CHECK(r.stats.passes == 1);
        for (std::size_t i = 0; i < r.samples.size(); ++i) CHECK(r.samples[i] == 8u);
    }
    SECTION("a noise target stops each texel when reached") {
        BakeSettings s = floor_settings(32);
        s.lighting.rounds = 4096;
        s.rounds_per_pass = 2;
        s.noise_target = 0.02;
        const BakeResult r = bake(scene, s);
        CHECK(r.stats.status == BakeStatus::NoiseTarget);
        for (std::size_t i = 0; i < r.noise.size(); ++i) CHECK(r.noise[i] <= 0.02f);
        CHECK(r.stats.max_relative_error <= 0.02);
    }
}

TEST_CASE("samples = N takes exactly N per texel", "[bake]") {
    Scene scene;
    Floor f;
    floor_scene(scene, f);
    // Counts per round 1 + 2 = 3: 16 is 4 whole rounds and a final one of 4.
    for (bool progressive : {false, true})
        for (long long n : {3LL, 16LL, 128LL, 1000LL}) {
            BakeSettings s = floor_settings(16);
            s.lighting.samples = {1, 2};
            s.samples = n;
            if (progressive) s.time_budget = 1000;  // passes, never reached
            const BakeResult r = bake(scene, s);
            INFO("samples " << n << (progressive ? " in passes" : " in one pass"));
            CHECK(r.stats.status == BakeStatus::Complete);
            CHECK(r.stats.samples == std::uint64_t(n) * r.stats.covered);
            for (std::uint32_t k : r.samples) CHECK(k == std::uint32_t(n));
        }
}

// The work behind the samples: draws counts every direction drawn, so it is
// N per texel where no texel is shadowed, and 4N more for each texel whose
// centre sees no light's middle point (shadowed_draws = 4). The scene makes
// that set known exactly: the unit floor (8² texels, centres at (i + ½)/8)
// under two small lights about x = 0.5, z = 2 (x ∈ [0.45, 0.55]) and an
// opaque sheet at z = 1 over x < 0.5. A ray from a texel centre at x to a
// light point at x_l crosses z = 1 at (x + x_l)/2: below 0.5 for every light
// point when x ≤ 7/16 (columns 0–3: shadowed), above it when x ≥ 9/16.
TEST_CASE("draws: N per texel, and exactly 4N where a texel's centre is shadowed", "[bake]") {
    std::vector<float> positions, uvs;
    std::vector<std::uint32_t> triangles;
    Scene scene;
    scene.add_mesh(grid_mesh(2, 0.0, 5, positions, triangles, uvs));
    const std::vector<float> sheet = {-10, -10, 1, 0.5f, -10, 1, 0.5f, 10, 1, -10, 10, 1};
    const std::vector<std::uint32_t> sheet_triangles = {0, 1, 2, 0, 2, 3};
    const std::vector<float> sheet_uvs(12, 0.f);
    scene.add_mesh(testing::two_triangle_mesh("sheet", sheet, sheet_triangles, sheet_uvs));
    for (double y : {0.25, 0.65})
        scene.add_light(make_rect_light(Vec3(0.45, y, 2), Vec3(0, 0.1, 0), Vec3(0.1, 0, 0),
                                        Vec3(5, 5, 5), false, kPi));
    scene.commit();
    constexpr long long kSamples = 48;  // rounds of 1 + 2
    constexpr int kShadowedColumns = 4, kSize = 8;
    for (bool progressive : {false, true})  // passes: the probe pass is replaced
        for (int shadowed_draws : {1, 4}) {
            BakeSettings s = floor_settings(kSize);
            s.lighting.samples = {1, 2};
            s.lighting.shadowed_draws = shadowed_draws;
            s.samples = kSamples;
            if (progressive) s.time_budget = 1000;  // never reached
            const BakeResult r = bake(scene, s);
            INFO("shadowed_draws " << shadowed_draws << (progressive ? ", passes" : ", one pass"));
            REQUIRE(r.stats.covered == std::size_t(kSize * kSize));
            const std::size_t shadowed =
                shadowed_draws > 1 ? std::size_t(kShadowedColumns * kSize) : 0;
            CHECK(r.stats.shadowed_texels == shadowed);
            CHECK(r.stats.samples == std::uint64_t(kSamples) * r.stats.covered);
            CHECK(r.stats.samples_per_texel == double(kSamples));
            for (std::uint32_t k : r.samples) CHECK(k == std::uint32_t(kSamples));
            const std::uint64_t draws =
                std::uint64_t(kSamples) * (r.stats.covered + 3 * shadowed);
            CHECK(r.stats.draws == draws);
            CHECK(r.stats.draws_per_texel == double(draws) / double(r.stats.covered));
        }
}

// A flat floor alone under its lights (the race's area scenes): a ray from
// a texel leaves the floor's plane and meets nothing, so the bake traces no
// shadow ray, the shadow probe's included (EffectPlan::shadow_rays). Its
// estimates must be those of the same floor with a mesh that hides nothing
// (a triangle under the floor), which traces them: bit for bit, the probe's
// verdicts as well (texels that see no light's middle point, here at the
// spread lamp's far end, are still found). The floor is tilted, so that its
// float vertices lie on its plane only within rounding.
TEST_CASE("a lone flat floor: no shadow rays, the estimates of one with a mesh that hides nothing",
          "[bake]") {
    std::vector<float> positions, uvs;
    std::vector<std::uint32_t> triangles;
    MeshInput floor = grid_mesh(5, 0.3, 9, positions, triangles, uvs);
    const double tilt = 0.3;  // radians about the x axis
    for (std::size_t i = 0; i < positions.size(); i += 3) {
        const double y = positions[i + 1];
        positions[i + 1] = float(y * std::cos(tilt));
        positions[i + 2] = float(y * std::sin(tilt));
    }
    auto build = [&](Scene& scene, bool hidden_triangle) {
        scene.add_mesh(floor);
        if (hidden_triangle)
            scene.add_mesh(std::vector<Vec3>{{0.4, 0.4, -0.5}, {0.6, 0.4, -0.5}, {0.5, 0.6, -0.5}},
                           {{0, 1, 2}});
        // Comparable local lamps (the plan's uniform selection and probe),
        // facing down over the floor's corner at the origin and spread over
        // 60°: the far corner's texels see neither one's middle point.
        scene.add_light(make_rect_light(Vec3(0.1, 0.1, 1.2), Vec3(0, 0.3, 0), Vec3(0.3, 0, 0),
                                        Vec3(8, 8, 8), false, kPi / 3));
        scene.add_light(make_rect_light(Vec3(0.05, 0.4, 1.3), Vec3(0, 0.2, 0), Vec3(0.2, 0, 0),
                                        Vec3(12, 12, 12), false, kPi / 3));
        scene.commit();
    };
    Scene alone, with_triangle;
    build(alone, false);
    build(with_triangle, true);
    for (bool passes : {false, true}) {
        BakeSettings s;
        s.width = s.height = 16;
        s.samples = 24;
        if (passes) s.time_budget = 1000;  // passes, never reached
        const BakeResult a = bake(alone, s), b = bake(with_triangle, s);
        INFO(a.stats.plan);
        INFO(b.stats.plan);
        CHECK(a.stats.plan.find("shadow rays: no") != std::string::npos);
        CHECK(b.stats.plan.find("shadow rays: yes") != std::string::npos);
        CHECK(a.stats.rays_traced == 0);
        CHECK(b.stats.rays_traced > 0);
        REQUIRE(a.stats.covered == b.stats.covered);
        CHECK(a.stats.shadowed_texels > 0);
        CHECK(a.stats.shadowed_texels == b.stats.shadowed_texels);
        CHECK(a.stats.draws == b.stats.draws);
        CHECK(a.value == b.value);
    }
}

TEST_CASE("a scene without lights bakes black (not NaN) with the asked sample count", "[bake]") {
    std::vector<float> positions, uvs;
    std::vector<std::uint32_t> triangles;
    Scene scene;
    scene.add_mesh(grid_mesh(2, 0.0, 3, positions, triangles, uvs));
    scene.commit();
    for (double budget : {0.0, 0.05}) {
        BakeSettings s;
        s.width = s.height = 8;
        s.samples = 16;
        s.time_budget = budget;
        const BakeResult r = bake(scene, s);
        for (float v : r.value) CHECK(v == 0.f);
        for (float e : r.noise) CHECK(e == 0.f);
        if (budget == 0)
            for (std::uint32_t k : r.samples) CHECK(k == 16u);
    }
}

TEST_CASE("footprint: every texel's samples lie in its triangle and in its UV square "
          "unless mirrored back from beyond the triangle's edge", "[bake]") {
    std::vector<float> positions, uvs;
    std::vector<std::uint32_t> triangles;
    Scene scene;
    scene.add_mesh(grid_mesh(5, 0.3, 7, positions, triangles, uvs));
    scene.commit();
    const Mesh& mesh = scene.geometry().mesh(0);
    const int size = 24;
    const UvCoverage cov = rasterize_uv(mesh, size, size);
    std::size_t inside_square = 0, samples = 0;
    for (std::size_t i = 0; i < cov.triangle.size(); ++i) {
        if (!cov.is_covered(i)) continue;
        const TexelFootprintMap map(mesh, cov, i);
        const std::uint32_t t = map.triangle();
        const auto& uv0 = mesh.corner_uvs[3 * t];
        const auto& uv1 = mesh.corner_uvs[3 * t + 1];
        const auto& uv2 = mesh.corner_uvs[3 * t + 2];
        const double cx = double(i % size) + 0.5, cy = double(i / size) + 0.5;
        for (int a = 0; a <= 8; ++a)
            for (int b = 0; b <= 8; ++b) {
                const double u = a / 8.0, v = b / 8.0;
                const auto bc = map.barycentrics(u, v);
                const double b0 = 1 - bc[0] - bc[1];
                ++samples;
                CHECK(bc[0] >= -1e-12);
                CHECK(bc[1] >= -1e-12);
                CHECK(b0 >= -1e-12);
                // The sample's texel coordinates.
                const double x = (b0 * uv0[0] + bc[0] * uv1[0] + bc[1] * uv2[0]) * size;
                const double y = (b0 * uv0[1] + bc[0] * uv1[1] + bc[1] * uv2[1]) * size;
                const double h = 0.5 * kTexelFootprintScale;
                const bool in_square = std::abs(x - cx) <= h + 1e-6 && std::abs(y - cy) <= h + 1e-6;
                inside_square += in_square;
                // Unmirrored, a sample is exactly the texel point (u, v) of the square.
                const double sx = cx + (u - 0.5) * 2 * h, sy = cy + (v - 0.5) * 2 * h;
                if (std::abs(x - sx) > 1e-6 || std::abs(y - sy) > 1e-6) {
                    // Mirrored: only where the point (u, v) itself lies beyond the triangle.
                    INFO("texel " << i << " (u, v) = (" << u << ", " << v << ")");
                    const double px = sx / size, py = sy / size;
                    const double d = (uv1[0] - uv0[0]) * (uv2[1] - uv0[1]) -
                                     (uv2[0] - uv0[0]) * (uv1[1] - uv0[1]);
                    const double l1 = ((px - uv0[0]) * (uv2[1] - uv0[1]) -
                                       (uv2[0] - uv0[0]) * (py - uv0[1])) / d;
                    const double l2 = ((uv1[0] - uv0[0]) * (py - uv0[1]) -
                                       (px - uv0[0]) * (uv1[1] - uv0[1])) / d;
                    CHECK((l1 < 1e-9 || l2 < 1e-9 || l1 + l2 > 1 - 1e-9));
                }
            }
    }
    // Most samples of most texels are interior ones.
    CHECK(inside_square > 0.8 * samples);
}

namespace {

// RMS over texels of the reported standard error and of the actual error
// (exact: Lambert over each footprint) of a floor bake.
struct NoiseCheck {
    double reported = 0, actual = 0;
};

NoiseCheck floor_noise(Strategy strategy, long long samples, double noise_target) {
    Scene scene;
    Floor f;
    floor_scene(scene, f);
    const int size = 24;
    const UvCoverage cov = rasterize_uv(scene.geometry().mesh(0), size, size);
    BakeSettings s = floor_settings(size);
    s.lighting.samples = {1, 1};
    s.lighting.strategy = strategy;
    s.samples = samples;
    s.noise_target = noise_target;
    s.lighting.seed = std::uint64_t(samples) * 7 + 1;
    const BakeResult r = bake(scene, s);
    NoiseCheck out;
    for (std::size_t i = 0; i < cov.triangle.size(); ++i) {
        const double sd = r.noise[i] * r.value[3 * i + 1];
        const double e = r.value[3 * i + 1] - lambert_footprint(scene, cov, i);
        out.reported += sd * sd;
        out.actual += e * e;
    }
    out.reported = std::sqrt(out.reported / cov.triangle.size());
    out.actual = std::sqrt(out.actual / cov.triangle.size());
    return out;
}

}  // namespace

// A target never met (1e-6) runs the bake to its sample count with the
// independent streams a noise target measures the error with, over several
// passes. Each RMS comes from 24² texels, so its own relative spread is
// ~1/√(2·576) ≈ 3 %; the bounds [0.8, 1.25] are the accuracy asked of the
// estimate.
void check_noise_target_calibration(Strategy strategy) {
    for (long long n : {16LL, 128LL, 1024LL}) {
        const NoiseCheck c = floor_noise(strategy, n, 1e-6);
        const double ratio = c.reported / c.actual;
        INFO(strategy_name(strategy) << ", " << n << " samples: estimated/true RMS error "
                                     << ratio);
        CHECK(ratio >= 0.8);
        CHECK(ratio <= 1.25);
    }
}

TEST_CASE("noise: a noise target's error estimate matches the true error at 16–1024 samples",
          "[bake]") {
    check_noise_target_calibration(Strategy::Balance);
}

// optimal-direct under a noise target: each stream is corrected with the α
// solved from the other streams (MisEstimator::stream_cross_fit), and the
// streams' mean is the estimate, so their spread includes the fit's error.
// (With one α fitted to all streams, that error was common to them and the
// estimate read 0.50–0.60 of the true error: a noise target stopped early.)
TEST_CASE("noise: optimal-direct's noise-target error estimate is calibrated", "[bake]") {
    check_noise_target_calibration(Strategy::OptimalDirect);
}

TEST_CASE("noise: one sequence per texel errs less, and its reported error bounds the true one",
          "[bake]") {
    // Without a noise target a texel's samples are one scrambled sequence: the
    // reported error is the independent-draw formula, which must not
    // under-state the true error (≥ 0.8, the calibration test's accuracy);
    // and the point of the single sequence is a smaller true error than the
    // noise target's four streams at the same count. On this smooth floor
    // the gap is large (the streams lose the stratification across them:
    // 2–5× in RMS error measured), far beyond the RMS's ~3 % spread.
    for (Strategy strategy : {Strategy::Balance, Strategy::OptimalDirect})
        for (long long n : {16LL, 128LL, 1024LL}) {
            const NoiseCheck one = floor_noise(strategy, n, 0);
            const NoiseCheck streams = floor_noise(strategy, n, 1e-6);
            INFO(strategy_name(strategy) << ", " << n << " samples: reported/true RMS error "
                                         << one.reported / one.actual << "; true RMS error "
                                         << one.actual << " (one sequence) vs " << streams.actual
                                         << " (streams)");
            CHECK(one.reported >= 0.8 * one.actual);
            CHECK(one.actual < streams.actual);
        }
}

TEST_CASE("cancel after 10 % returns promptly", "[bake]") {
    Scene scene;
    Floor f;
    floor_scene(scene, f);
    BakeSettings s = floor_settings(256);
    s.lighting.rounds = 64;
    using Clock = std::chrono::steady_clock;
    Clock::time_point cancelled_at{};
    const BakeResult r = bake(scene, s, [&](double fraction) {
        if (fraction < 0.1) return true;
        if (cancelled_at == Clock::time_point{}) cancelled_at = Clock::now();
        return false;
    });
    const double latency = std::chrono::duration<double>(Clock::now() - cancelled_at).count();
    CHECK(r.stats.status == BakeStatus::Cancelled);
    CHECK(latency < 0.5);
}

TEST_CASE("bad bake input gives clear errors", "[bake]") {
    using Catch::Matchers::Contains;
    Scene scene;
    std::vector<float> p = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    std::vector<std::uint32_t> t = {0, 1, 2};
    MeshInput no_uv;
    no_uv.name = "plane";
    no_uv.positions = ScalarArray::of(p.data(), 3, 3);
    no_uv.triangles = IndexArray{t.data(), 1, 3};
    scene.add_mesh(no_uv);
    std::vector<float> nan_p = {0, 0, 0, NAN, 0, 0, 0, 1, 0};
    MeshInput bad = no_uv;
    bad.positions = ScalarArray::of(nan_p.data(), 3, 3);
    CHECK_THROWS_WITH(scene.add_mesh(bad), Contains("not finite"));
    scene.add_light(make_point_light(Vec3(0, 0, 1), Vec3(1, 1, 1), 0));
    BakeSettings s = floor_settings(16);
    CHECK_THROWS_WITH(bake(scene, s), Contains("not committed"));
    scene.commit();
    CHECK_THROWS_WITH(bake(scene, s), Contains("no UV map"));
    s.mesh = 5;
    CHECK_THROWS_WITH(bake(scene, s), Contains("out of range"));
    s.target = BakeTarget::Vertices;
    s.mesh = 0;
    CHECK_NOTHROW(bake(scene, s));

    Scene with_uv;
    Floor f;
    floor_scene(with_uv, f);
    BakeSettings z = floor_settings(0);
    CHECK_THROWS_WITH(bake(with_uv, z), Contains("size"));
    z.width = z.height = 1 << 20;
    CHECK_THROWS_WITH(bake(with_uv, z), Contains("beyond"));
}
