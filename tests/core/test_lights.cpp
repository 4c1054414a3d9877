// The light dispatch (core/lights: sample_light, light_pdf, sampler_applies) run
// through the sampler checker of the sampling tests (sampler_check.h) for every
// light type and every shape sampler that applies. The shape samplers themselves
// are checked against exact cell probabilities in test_sampling.cpp; here the
// question is whether the dispatch hands each light and sampler to a matching
// sample/pdf pair, so the reference comes from light_pdf alone: cells of equal
// solid angle on a cap of directions around the light, their probabilities
// integrated from light_pdf by the midpoint rule.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "lights/light.h"
#include "sampler_check.h"

using namespace omis;
using namespace omis::testing;

namespace {

const ShapeSampler kSamplers[] = {ShapeSampler::Area, ShapeSampler::SolidAngle,
                                  ShapeSampler::Parallel, ShapeSampler::ProjectedSolidAngle};

// A light seen from a shading point, and the samplers expected to apply there
// (SPEC §3: parallel needs a planar or disk shape wholly above the horizon; sun
// and world have no shape and take every other sampler; delta lights, and lights
// that cannot reach the point, none).
struct LightCase {
    std::string what;  // for messages only
    Light light;
    Vec3 x, n;
    std::vector<ShapeSampler> applies;
};

const Vec3 kUp{0, 0, 1};
const Vec3 kGrey{1, 1, 1};
const std::vector<ShapeSampler> kAll(std::begin(kSamplers), std::end(kSamplers));
const std::vector<ShapeSampler> kNoParallel = {ShapeSampler::Area, ShapeSampler::SolidAngle,
                                               ShapeSampler::ProjectedSolidAngle};

std::vector<LightCase> light_cases() {
    return {
        {"rect facing down", make_rect_light({-0.5, -0.3, 1}, {0, 0.6, 0}, {1, 0, 0}, kGrey, false, kPi),
         {}, kUp, kAll},
        {"rect two-sided, tilted, seen from its back",
         make_rect_light({0.2, -0.5, 0.8}, {0.6, 0, 0.3}, {0, 0.5, 0}, kGrey, true, kPi),
         {}, kUp, kAll},
        {"rect 4 m wide, spread 1 rad: only a part reaches x",
         make_rect_light({-2, -2, 1}, {0, 4, 0}, {4, 0, 0}, kGrey, false, 1.0), {}, kUp, kAll},
        {"rect straddling the horizon",
         make_rect_light({-0.5, 1, -0.3}, {1, 0, 0}, {0, 0, 0.8}, kGrey, false, kPi), {}, kUp,
         kNoParallel},
        {"disk facing down",
         make_ellipse_light({0.3, 0.2, 1.2}, {0.4, 0, 0}, {0, -0.4, 0}, kGrey, false, kPi), {},
         kUp, kAll},
        {"ellipse 4 × 3 m, spread 0.8 rad: clipped",
         make_ellipse_light({0, 0, 1}, {2, 0, 0}, {0, -1.5, 0}, kGrey, false, 0.8), {}, kUp,
         kAll},
        {"triangle facing down",
         make_triangle_light({-0.5, -0.5, 1}, {0, 0.7, 0.9}, {0.6, -0.4, 1.1}, kGrey, false), {},
         kUp, kAll},
        {"triangle two-sided, tilted receiver",
         make_triangle_light({-0.5, -0.5, 1}, {0.6, -0.4, 1.1}, {0, 0.7, 0.9}, kGrey, true),
         {0.2, 0.1, 0}, normalize(Vec3{0.3, 0, 1}), kAll},
        {"point light, radius 0.2", make_point_light({0.5, 0.2, 1}, kGrey, 0.2), {}, kUp, kAll},
        {"spot light, radius 0.3",
         make_spot_light({0, 0.3, 1.5}, {0, 0, -1}, kGrey, 0.3, 1.2, 0.2), {}, kUp, kAll},
        {"sun, 0.3 rad across", make_sun_light({0.2, -0.3, -1}, kGrey, 0.3), {}, kUp,
         kNoParallel},
        {"world", make_world_light(kGrey), {}, normalize(Vec3{0.2, 0.5, 1}), kNoParallel},
        // No sampler: delta lights, and emitters that cannot reach x.
        {"point light, radius 0", make_point_light({0, 0, 1}, kGrey, 0), {}, kUp, {}},
        {"spot light, radius 0", make_spot_light({0, 0, 1}, {0, 0, -1}, kGrey, 0, 1, 0.1), {},
         kUp, {}},
        {"sun, angle 0", make_sun_light({0, 0, -1}, kGrey, 0), {}, kUp, {}},
        {"rect facing away", make_rect_light({-0.5, -0.3, 1}, {1, 0, 0}, {0, 0.6, 0}, kGrey, false, kPi),
         {}, kUp, {}},
        {"disk below the horizon",
         make_ellipse_light({0, 0, -1}, {0.4, 0, 0}, {0, 0.4, 0}, kGrey, true, kPi), {}, kUp, {}},
    };
}

constexpr int kCells = 8;   // K × K cells: K bands equal in cos θ, K sectors of φ
constexpr int kSub = 32;    // midpoint rule: kSub × kSub sub-cells per cell

// A cap of directions around an axis, cut into cells of equal solid angle.
struct Cap {
    Frame frame;
    double cos_max;

    double height() const { return 1 - cos_max; }  // solid angle / 2π
    int bin(const Vec3& w) const {
        const Vec3 l = frame.to_local(w);
        if (l.z < cos_max - 1e-12) return -1;
        const int i = std::clamp(int((1 - l.z) / height() * kCells), 0, kCells - 1);
        double phi = std::atan2(l.y, l.x) / (2 * kPi);
        if (phi < 0) phi += 1;
        const int j = std::clamp(int(phi * kCells), 0, kCells - 1);
        return i * kCells + j;
    }
    // Direction at fractional grid position (a, b) ∈ [0, K)²: a along 1 − cos θ, b along φ.
    Vec3 direction(double a, double b) const {
        const double z = 1 - height() * a / kCells, r = std::sqrt(std::max(0.0, 1 - z * z));
        const double phi = 2 * kPi * b / kCells;
        return frame.to_world({r * std::cos(phi), r * std::sin(phi), z});
    }
};

// The cap that holds the sampler's draws: around their mean direction, 2% and
// 0.02 rad wider than the widest of 4096 pilot draws (their own seed). A cap
// that missed part of the support would show as cell probabilities summing to
// less than 1 and as unbinned draws, both checked.
Cap cap_of(const std::function<std::optional<LightSample>(double, double)>& sample,
           std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    std::vector<Vec3> dirs;
    Vec3 sum;
    for (int i = 0; i < 4096; ++i) {
        const double u1 = uni(rng), u2 = uni(rng);
        if (const auto s = sample(u1, u2)) {
            dirs.push_back(s->dir);
            sum += s->dir;
        }
    }
    REQUIRE(!dirs.empty());
    const Vec3 axis = normalize(sum);
    double widest = 0;
    for (const Vec3& d : dirs) widest = std::max(widest, angle_between(axis, d));
    return {Frame(axis), std::cos(std::min(kPi, 1.02 * widest + 0.02))};
}

// Cell probabilities, the support's solid angle and their error bounds, from
// light_pdf at the middle of every sub-cell. Inside the support the pdf is
// smooth and the midpoint rule is exact to O(sub-cell²); the error sits in the
// sub-cells the support's edge crosses, found as those whose neighbour differs
// in being inside: each is off by at most its area (times the nearby pdf).
void integrate_cells(const Cap& cap, const std::function<double(const Vec3&)>& pdf,
                     SamplerUnderTest& t) {
    const int n = kCells * kSub;
    const double area = 2 * kPi * cap.height() / (double(n) * n);
    std::vector<double> p(std::size_t(n) * n);
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b)
            p[std::size_t(a) * n + b] = pdf(cap.direction((a + 0.5) / kSub, (b + 0.5) / kSub));
    t.cell_prob.assign(kCells * kCells, 0.0);
    double measure = 0, edge_area = 0, edge_mass = 0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const double here = p[std::size_t(a) * n + b];
            t.cell_prob[(a / kSub) * kCells + b / kSub] += here * area;
            if (here > 0) measure += area;
            double nearby = here;
            bool edge = false;
            for (auto [da, db] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
                const int a2 = a + da, b2 = (b + db + n) % n;  // φ wraps around
                if (a2 < 0 || a2 >= n) continue;
                const double there = p[std::size_t(a2) * n + b2];
                edge |= (there > 0) != (here > 0);
                nearby = std::max(nearby, there);
            }
            if (edge) {
                edge_area += area;
                edge_mass += area * nearby;
            }
        }
    t.measure = measure;
    t.measure_tol = edge_area / measure + 1e-4;
    t.prob_sum_tol = edge_mass + 1e-4;
}

}  // namespace

TEST_CASE("light dispatch: which samplers apply", "[lights]") {
    for (const LightCase& c : light_cases()) {
        INFO(c.what);
        for (ShapeSampler s : kSamplers) {
            INFO("sampler " << shape_sampler_name(s));
            const bool expected =
                std::find(c.applies.begin(), c.applies.end(), s) != c.applies.end();
            CHECK(sampler_applies(c.light, s, c.x, c.n) == expected);
            if (c.light.is_delta()) {
                // Delta lights are lit by one shadow ray (delta_illumination) only.
                CHECK_FALSE(sample_light(c.light, s, c.x, c.n, 0.3, 0.6));
                CHECK(light_pdf(c.light, s, c.x, c.n, normalize(c.light.position - c.x)) == 0);
            }
        }
    }
}

TEST_CASE("light dispatch: sample_light and light_pdf agree", "[lights]") {
    std::uint64_t seed = 20000;
    for (const LightCase& c : light_cases()) {
        for (ShapeSampler s : c.applies) {
            SamplerUnderTest t;
            t.name = std::string(c.what) + ", " + shape_sampler_name(s);
            t.sample = [&](double u1, double u2) { return sample_light(c.light, s, c.x, c.n, u1, u2); };
            t.pdf = [&](const Vec3& w) { return light_pdf(c.light, s, c.x, c.n, w); };
            const Cap cap = cap_of(t.sample, seed++);
            t.bin = [cap](const Vec3& w) { return cap.bin(w); };
            integrate_cells(cap, t.pdf, t);
            t.finite_dist = c.light.type != LightType::Sun && c.light.type != LightType::World;
            run_sampler_check(t, seed++);
        }
    }
}
