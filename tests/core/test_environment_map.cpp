// The image-based world (lights/environment_map.h): Cycles' equirectangular
// convention, its importance sampling under the shared sampler checker, and
// direct lighting from it against exact answers (a constant map, one bright
// texel). Statistical checks: the mean of T independent copies within 4
// standard errors measured from the copies (a 6e-5 miss for a normal mean;
// fixed seeds make a pass reproducible).
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "lights/environment_map.h"
#include "lights/light.h"
#include "render/direct_lighting.h"
#include "render/scene.h"
#include "sampler_check.h"
#include "support/lighting_settings.h"
#include "support/point_copies.h"

using namespace omis;

namespace {

constexpr double kSigmas = 4.0;
constexpr int kCopies = 64;

std::vector<float> constant_rgb(int w, int h, const Vec3& c) {
    std::vector<float> rgb;
    for (int i = 0; i < w * h; ++i)
        rgb.insert(rgb.end(), {float(c.x), float(c.y), float(c.z)});
    return rgb;
}

std::vector<float> random_rgb(int w, int h, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    std::vector<float> rgb(std::size_t(w) * h * 3);
    // Log-uniform over four decades: a sky's range of texels, no zero.
    for (float& v : rgb) v = float(std::pow(10.0, 4 * uni(rng) - 2));
    return rgb;
}

// Texel (column, row) of a world direction, by the formulas of Cycles'
// direction_to_equirectangular written out here (rows top first).
std::pair<int, int> texel_of(const Vec3& d, int w, int h) {
    double u = (std::atan2(d.y, d.x) - kPi) / (-2 * kPi);
    const double v = (std::acos(std::max(-1.0, std::min(1.0, d.z))) - kPi) / (-kPi);
    if (u >= 1) u -= 1;
    const int column = std::min(int(u * w), w - 1),
              row = std::min(int((1 - v) * h), h - 1);
    return {column, row};
}

double texel_solid_angle(int row, int w, int h) {
    return 2 * kPi / w * (std::cos(kPi * row / h) - std::cos(kPi * (row + 1) / h));
}

std::unique_ptr<Scene> world_scene(const Light& world) {
    auto scene = std::make_unique<Scene>();
    scene->add_light(world);
    scene->commit();
    return scene;
}

testing::PointCopies copies(const Scene& scene, const Vec3& n,
                            const std::vector<std::string>& names,
                            const std::vector<int>& samples, Strategy strategy,
                            std::uint64_t seed) {
    return testing::light_point_copies(
        scene, Vec3(0, 0, 0), n,
        testing::lighting_settings(names, samples, 1, strategy, seed), kCopies);
}

// R·v for the Mapping node's Euler XYZ rotation e, R = Rz·Ry·Rx, written out
// here independently of the map's own rotation.
Vec3 euler_xyz(const Vec3& e, Vec3 v) {
    v = {v.x, std::cos(e.x) * v.y - std::sin(e.x) * v.z,
         std::sin(e.x) * v.y + std::cos(e.x) * v.z};
    v = {std::cos(e.y) * v.x + std::sin(e.y) * v.z, v.y,
         -std::sin(e.y) * v.x + std::cos(e.y) * v.z};
    return {std::cos(e.z) * v.x - std::sin(e.z) * v.y,
            std::sin(e.z) * v.x + std::cos(e.z) * v.y, v.z};
}

}  // namespace

TEST_CASE("equirectangular convention: Cycles' direction_to_equirectangular",
          "[envmap]") {
    using M = EnvironmentMap;
    // +X is the image's centre, u grows toward −Y, v = 1 at the zenith.
    CHECK(M::direction_to_equirectangular({1, 0, 0}).x == Approx(0.5));
    CHECK(M::direction_to_equirectangular({1, 0, 0}).y == Approx(0.5));
    CHECK(M::direction_to_equirectangular({0, -1, 0}).x == Approx(0.75));
    CHECK(M::direction_to_equirectangular({0, 1, 0}).x == Approx(0.25));
    CHECK(M::direction_to_equirectangular({-1, 0, 0}).x == Approx(0.0).margin(1e-12));
    CHECK(M::direction_to_equirectangular({0, 0, 1}).y == Approx(1.0));
    CHECK(M::direction_to_equirectangular({0, 0, -1}).y == Approx(0.0).margin(1e-12));
    std::mt19937_64 rng(5);
    std::normal_distribution<double> g;
    for (int i = 0; i < 1000; ++i) {
        const Vec3 d = normalize(Vec3(g(rng), g(rng), g(rng)));
        const Vec3 back =
            M::equirectangular_to_direction(M::direction_to_equirectangular(d));
        CHECK(length(back - d) < 1e-12);
    }
}

TEST_CASE("world image rotation: the Mapping node's Euler XYZ turns the lookup",
          "[envmap]") {
    const int w = 16, h = 8;
    const std::vector<float> rgb = random_rgb(w, h, 3);
    auto at = [&](int column, int row) {
        const float* p = &rgb[(std::size_t(row) * w + column) * 3];
        return Vec3(p[0], p[1], p[2]);
    };
    // Rz(90°) takes +X to +Y: the world's +X sees the texel of map direction +Y.
    const EnvironmentMap z90(rgb, w, h, Vec3(0, 0, kPi / 2), false);
    const Vec3 x_dir = normalize(Vec3(1, 0.01, 0.2));
    const Vec3 turned{-x_dir.y, x_dir.x, x_dir.z};
    const auto [c, r] = texel_of(turned, w, h);
    CHECK(length(z90.radiance(x_dir) - at(c, r)) == 0);
    // R = Rz·Ry·Rx: a general rotation against the product written out.
    const Vec3 e(0.3, -1.1, 2.0);
    const EnvironmentMap rotated(rgb, w, h, e, false);
    std::mt19937_64 rng(9);
    std::normal_distribution<double> g;
    for (int i = 0; i < 200; ++i) {
        const Vec3 d = normalize(Vec3(g(rng), g(rng), g(rng)));
        const Vec3 v = euler_xyz(e, d);
        const auto [col, row] = texel_of(v, w, h);
        CHECK(length(rotated.radiance(d) - at(col, row)) == 0);
    }
}

TEST_CASE("world image sampler: pdf, inversion, measure and chi-square", "[envmap]") {
    const int w = 12, h = 6;
    std::uint64_t seed = 101;
    for (bool compensate : {false, true})
        for (const Vec3& rotation : {Vec3(0, 0, 0), Vec3(0.4, -0.7, 1.9)}) {
            const std::vector<float> rgb = random_rgb(w, h, seed);
            const EnvironmentMap map(rgb, w, h, rotation, compensate);
            // The expected draw probability of each texel, from its luminance
            // (minus the mean with compensation) × the row's mean sin θ.
            std::vector<double> lum(w * h), prob(w * h);
            double mean = 0, total = 0, measure = 0;
            for (int i = 0; i < w * h; ++i) {
                lum[i] = luminance(Vec3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]));
                mean += lum[i] * texel_solid_angle(i / w, w, h) / (4 * kPi);
            }
            for (int i = 0; i < w * h; ++i) {
                const int row = i / w;
                const double l = compensate ? std::max(0.0, lum[i] - mean) : lum[i];
                const double band =
                    std::cos(kPi * row / h) - std::cos(kPi * (row + 1) / h);
                prob[i] = l * band / (kPi / h);
                total += prob[i];
                if (l > 0) measure += texel_solid_angle(row, w, h);
            }
            for (double& p : prob) p /= total;
            const std::array<Vec3, 3> to_map = [&] {
                std::array<Vec3, 3> m;
                for (int k = 0; k < 3; ++k) {
                    // Columns of R from the lookups of the axes are not
                    // exposed; rotate by the same Euler product as above.
                    const Vec3 v =
                        k == 0 ? Vec3(1, 0, 0) : (k == 1 ? Vec3(0, 1, 0) : Vec3(0, 0, 1));
                    m[k] = euler_xyz(rotation, v);  // R·axis_k
                }
                return m;
            }();
            testing::SamplerUnderTest t;
            t.name = std::string("world image") + (compensate ? ", compensated" : "");
            t.sample = [&](double u1, double u2) { return map.sample(u1, u2); };
            t.pdf = [&](const Vec3& d) { return map.pdf(d); };
            t.invert = [&](const Vec3& d) {
                return std::optional<Point2>(map.invert(d));
            };
            t.bin = [&](const Vec3& d) {
                const Vec3 m = to_map[0] * d.x + to_map[1] * d.y + to_map[2] * d.z;
                const auto [c, r] = texel_of(m, w, h);
                return r * w + c;
            };
            t.cell_prob = prob;
            t.measure = measure;
            t.invert_tol = 1e-5;    // float CDFs
            t.finite_dist = false;  // a world is infinitely far
            testing::run_sampler_check(t, seed++);
        }
}

TEST_CASE("a constant map is the constant world", "[envmap]") {
    const Vec3 c(0.75, 1.5, 0.25);  // exact in float, as the map stores them
    auto map = std::make_shared<EnvironmentMap>(constant_rgb(64, 32, c), 64, 32,
                                                Vec3(0.2, 0.5, 1), true);
    CHECK(!map->compensation_applied());  // nothing above the mean
    const Light image = make_environment_light(map), constant = make_world_light(c);
    CHECK(length(image.emission - c) <= 1e-12 * length(c));
    CHECK(image.power(3.0) == Approx(constant.power(3.0)).epsilon(1e-12));
    const auto image_scene = world_scene(image), constant_scene = world_scene(constant);
    const Vec3 n = normalize(Vec3(0.3, -0.2, 1));
    // Cosine draws see the same radiance: the same bits.
    const auto a = copies(*image_scene, n, {"bsdf"}, {16}, Strategy::Balance, 7);
    const auto b = copies(*constant_scene, n, {"bsdf"}, {16}, Strategy::Balance, 7);
    CHECK(a.mean == b.mean);
    CHECK(a.mean == Approx(c.y).epsilon(1e-12));
    // The map's own draws (with cosine draws beside them) are unbiased.
    for (Strategy s : {Strategy::Balance, Strategy::OptimalDirect}) {
        const auto e =
            copies(*image_scene, n, {"uniform/solid-angle", "bsdf"}, {8, 8}, s, 11);
        INFO(strategy_name(s) << ": " << e.mean << " ± " << e.standard_error);
        CHECK(e.finite);
        CHECK(std::abs(e.mean - c.y) <= kSigmas * e.standard_error + 1e-12 * c.y);
    }
}

TEST_CASE("one bright texel against its closed form", "[envmap]") {
    // A coarse map: a cosine draw meets the texel with probability 1/16, so
    // the 1024 cosine draws of the copies below meet it ~64 times and their
    // share of a combined estimate (n_b p_b / Σ n p, ~3 % here) is resolved
    // by the copies' spread; a texel met once in all copies leaves an error
    // of that share which the spread cannot show.
    const int w = 8, h = 4;
    const int column = 5, row = 1;  // u in [0.625, 0.75), θ in [45°, 90°]
    const double L = 500;
    std::vector<float> rgb(std::size_t(w) * h * 3, 0.0f);
    for (int k = 0; k < 3; ++k) rgb[(std::size_t(row) * w + column) * 3 + k] = float(L);
    const Vec3 n(0, 0, 1);
    // E/π = (L/π) ∫ cos θ dω over the texel = (L/π)(2π/w)(sin²θ1 − sin²θ0)/2.
    const double t0 = kPi * row / h, t1 = kPi * (row + 1) / h;
    const double exact = L / kPi * (2 * kPi / w) *
                         (std::sin(t1) * std::sin(t1) - std::sin(t0) * std::sin(t0)) / 2;
    std::uint64_t seed = 31;
    for (bool compensate : {false, true}) {
        auto map = std::make_shared<EnvironmentMap>(rgb, w, h, Vec3(0, 0, 0), compensate);
        const auto scene = world_scene(make_environment_light(map));
        const std::pair<std::vector<std::string>, std::vector<int>> cases[] = {
            {{"uniform/solid-angle"}, {32}}, {{"uniform/solid-angle", "bsdf"}, {16, 16}}};
        for (const auto& [names, samples] : cases)
            for (Strategy s : {Strategy::Balance, Strategy::Power,
                               Strategy::OptimalDirect, Strategy::OptimalProgressive}) {
                if (compensate && names.size() == 1) {
                    // Compensation leaves the texels below the mean to `bsdf`:
                    // without it the call is refused, not biased.
                    CHECK_THROWS_WITH(copies(*scene, n, names, samples, s, seed++),
                                      Catch::Matchers::Contains("MIS compensation"));
                    continue;
                }
                const auto e = copies(*scene, n, names, samples, s, seed++);
                INFO(names.size() << " technique(s), " << strategy_name(s)
                                  << ", compensate " << compensate << ": " << e.mean
                                  << " ± " << e.standard_error << ", exact " << exact);
                CHECK(e.finite);
                CHECK(std::abs(e.mean - exact) <=
                      kSigmas * e.standard_error + 1e-9 * exact);
            }
    }
}

TEST_CASE("world image: bad input is refused with a clear message", "[envmap]") {
    using Catch::Matchers::Contains;
    auto make = [](std::vector<float> rgb, int w, int h, Vec3 rotation = {}) {
        return EnvironmentMap(std::move(rgb), w, h, rotation, false);
    };
    std::vector<float> rgb = constant_rgb(4, 2, Vec3(1, 1, 1));
    CHECK_THROWS_WITH(make(rgb, 4, 3), Contains("expected width x height x 3"));
    CHECK_THROWS_WITH(make(rgb, 0, 2), Contains("width and height"));
    CHECK_THROWS_WITH(make(rgb, 4, 2, Vec3(0, NAN, 0)),
                      Contains("rotation must be finite"));
    rgb[3 * 5 + 1] = NAN;
    CHECK_THROWS_WITH(make(rgb, 4, 2), Contains("row 1, column 1, channel 1) is NaN"));
    rgb[3 * 5 + 1] = -1;
    CHECK_THROWS_WITH(make(rgb, 4, 2), Contains("is negative"));
    rgb[3 * 5 + 1] = INFINITY;
    CHECK_THROWS_WITH(make(rgb, 4, 2), Contains("is infinite"));
}
