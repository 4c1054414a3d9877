// `unoccluded` selection's weight of a light with spread (lights/light.h,
// unoccluded_irradiance) against the spread-weighted Lambert integral
// (SPEC §4) computed here by a fine midpoint rule over the light.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>

#include "lights/light.h"

using namespace omis;

namespace {

// SPEC §4: radiance × max(0, 1 − tan a tan θ) · 2/(2 + (2a − π) tan a),
// a = (π − s)/2, θ the angle to the light's normal.
double spec_spread_factor(double cos_theta, double spread) {
    const double a = (kPi - spread) / 2, tan_a = std::tan(a);
    const double tan_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta)) / cos_theta;
    return std::max(0.0, 1 - tan_a * tan_theta) * 2 / (2 + (2 * a - kPi) * tan_a);
}

// ∫ L g(θ_l) cos⁺θ_x cos θ_l / r² dA over the points at(α, β) of the light,
// (α, β) in the box, by an m × m midpoint rule; `area` is dA/(dα dβ). The
// box is the spread's reach (the disk of radius z tan(s/2) about x's foot)
// cut to the light, so the rule resolves it however small it is.
double reference(const Vec3& x, const Vec3& n, const Vec3& normal, double spread,
                 const std::function<Vec3(double, double)>& at,
                 const std::function<bool(double, double)>& inside, double a0, double a1,
                 double b0, double b1, double area) {
    const int m = 1000;
    const double da = (a1 - a0) / m, db = (b1 - b0) / m;
    double sum = 0;
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
            const double a = a0 + (i + 0.5) * da, b = b0 + (j + 0.5) * db;
            if (!inside(a, b)) continue;
            const Vec3 d = at(a, b) - x;
            const double r2 = dot(d, d), r = std::sqrt(r2);
            const double cos_x = dot(n, d) / r, cos_l = -dot(normal, d) / r;
            if (cos_x <= 0 || cos_l <= 0) continue;
            sum += spec_spread_factor(cos_l, spread) * cos_x * cos_l / r2;
        }
    return sum * da * db * area;
}

struct Case {
    Vec3 x, n;
    double spread;
};

const Case kCases[] = {
    {Vec3(0.3, 0.1, 0.4), Vec3(0, 0, -1), 0.3},
    {Vec3(0.3, 0.1, 0.4), Vec3(0, 0, -1), 1.0},
    {Vec3(0.3, 0.1, 0.4), Vec3(0, 0, -1), 2.0},
    {Vec3(0.3, 0.1, 0.4), Vec3(0, 0, -1), 2.8},
    {Vec3(0.85, 0.4, 0.2), normalize(Vec3(0.5, 0, -1)), 1.0},  // near a corner, tilted
    {Vec3(0.85, 0.4, 0.2), normalize(Vec3(0.5, 0, -1)), 2.5},
    {Vec3(1.3, -0.2, 0.5), normalize(Vec3(-1, 0, -1)), 1.5},  // beside the light
    {Vec3(0.0, 0.0, 3.0), Vec3(0, 0, -1), 0.6},                // far above
    {Vec3(-0.4, 0.2, 0.05), Vec3(0, 0, -1), 2.0},              // 5 cm from it
};

// The weight's design accuracy, 10 %: a selection weight's error moves noise,
// never the mean, and it is computed per texel and pass — a 1 % design (6²/8²
// cells) cost 4× the samples per texel on the race's spread scenes. One that
// ignored the spread's shape is off by up to 2× here.
constexpr double kTolerance = 0.10;

}  // namespace

TEST_CASE("the unoccluded weight of a rect with spread is its spread-weighted irradiance",
          "[lights][spread]") {
    // 2 m × 1 m in the plane z = 0, emitting toward +z.
    const Vec3 corner(-1, -0.5, 0), eu(2, 0, 0), ev(0, 1, 0), normal(0, 0, 1);
    for (const Case& c : kCases) {
        INFO("x " << c.x.x << "," << c.x.y << "," << c.x.z << " spread " << c.spread);
        const Light l = make_rect_light(corner, eu, ev, Vec3(1, 1, 1), false, c.spread);
        const double radius = c.x.z * std::tan(c.spread / 2);
        const double fa = (c.x.x - corner.x) / 2, fb = (c.x.y - corner.y) / 1;
        const double a0 = std::max(0.0, fa - radius / 2), a1 = std::min(1.0, fa + radius / 2);
        const double b0 = std::max(0.0, fb - radius), b1 = std::min(1.0, fb + radius);
        const double exact = reference(
            c.x, c.n, normal, c.spread, [&](double a, double b) { return corner + eu * a + ev * b; },
            [](double, double) { return true; }, a0, a1, b0, b1, 2.0);
        REQUIRE(exact > 0);
        INFO("relative error " << unoccluded_irradiance(l, c.x, c.n) / exact - 1);
        CHECK(unoccluded_irradiance(l, c.x, c.n) == Approx(exact).epsilon(kTolerance));
    }
}

TEST_CASE("the unoccluded weight of an ellipse with spread is its spread-weighted irradiance",
          "[lights][spread]") {
    // Semi-axes 1 m and 0.6 m in the plane z = 0, emitting toward +z.
    const Vec3 centre(0, 0, 0), axis_a(1, 0, 0), axis_b(0, 0.6, 0), normal(0, 0, 1);
    for (const Case& c : kCases) {
        INFO("x " << c.x.x << "," << c.x.y << "," << c.x.z << " spread " << c.spread);
        const Light l = make_ellipse_light(centre, axis_a, axis_b, Vec3(1, 1, 1), false, c.spread);
        const double radius = c.x.z * std::tan(c.spread / 2);
        const double fa = c.x.x / 1, fb = c.x.y / 0.6;
        const double a0 = std::max(-1.0, fa - radius), a1 = std::min(1.0, fa + radius);
        const double b0 = std::max(-1.0, fb - radius / 0.6), b1 = std::min(1.0, fb + radius / 0.6);
        if (!(a0 < a1 && b0 < b1)) continue;
        const double exact = reference(
            c.x, c.n, normal, c.spread,
            [&](double a, double b) { return centre + axis_a * a + axis_b * b; },
            [](double a, double b) { return a * a + b * b <= 1; }, a0, a1, b0, b1, 0.6);
        if (exact == 0) {
            CHECK(unoccluded_irradiance(l, c.x, c.n) == 0);
            continue;
        }
        INFO("relative error " << unoccluded_irradiance(l, c.x, c.n) / exact - 1);
        CHECK(unoccluded_irradiance(l, c.x, c.n) == Approx(exact).epsilon(kTolerance));
    }
}
