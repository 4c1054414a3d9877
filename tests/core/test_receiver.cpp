// The receiver closures (render/receiver.h) against Cycles 3.4's formulas
// written out independently here, and their effect on direct lighting and bakes.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "bake/bake.h"
#include "bake/vertex_points.h"
#include "render/direct_lighting.h"
#include "render/receiver.h"
#include "render/techniques.h"

using namespace omis;
using Catch::Matchers::Contains;

namespace {

Vec3 dir(double theta, double phi) {
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// Burley 2012, "Physically Based Shading at Disney", eq. (3), in its original
// product form: f_d = (1/π)(1 + (F_D90 − 1)(1 − cosθ_l)⁵)(1 + (F_D90 − 1)(1 − cosθ_v)⁵),
// F_D90 = 1/2 + 2 r cos²θ_d, θ_d the angle between l and the half vector.
double burley(double r, const Vec3& n, const Vec3& v, const Vec3& l) {
    const Vec3 h = normalize(l + v);
    const double cd = dot(l, h), fd90 = 0.5 + 2 * r * cd * cd;
    const double cl = dot(n, l), cv = dot(n, v);
    return (1 + (fd90 - 1) * std::pow(1 - cl, 5)) * (1 + (fd90 - 1) * std::pow(1 - cv, 5)) / kPi;
}

}  // namespace

TEST_CASE("principled diffuse matches Burley's product form", "[receiver]") {
    const Vec3 n(0, 0, 1);
    for (double r : {0.0, 0.25, 0.5, 1.0})
        for (double tv : {0.0, 0.4, 1.0, 1.45})
            for (double tl : {0.05, 0.7, 1.2, 1.5}) {
                const Vec3 v = dir(tv, 0.3), l = dir(tl, 2.1);
                INFO("r " << r << " θv " << tv << " θl " << tl);
                CHECK(principled_diffuse_closure(n, v, l, r) ==
                      Approx(burley(r, n, v, l) * std::cos(tl)).epsilon(1e-12));
            }
}

TEST_CASE("the bake's view along the normal: receiver factors", "[receiver]") {
    const Vec3 n(0, 0, 1);
    const std::vector<double> angles = {0.0, 0.3, kPi / 3, 1.2, 79 * kPi / 180, 1.55};
    for (double r : {0.0, 0.5, 1.0}) {
        const Receiver p = make_receiver(ReceiverModel::PrincipledDiffuse, r);
        for (double t : angles) {
            const double c = std::cos(t);
            INFO("r " << r << " θ " << t);
            CHECK(receiver_cosine_factor(p, c) ==
                  Approx(principled_diffuse_closure(n, n, dir(t, 0.7), r)).epsilon(1e-12));
            CHECK(receiver_cosine_factor(p, c) == Approx(burley(r, n, n, dir(t, 0.7)) * c));
        }
    }
    // Normal incidence: F = 0, the principled diffuse is Lambert.
    CHECK(make_receiver(ReceiverModel::PrincipledDiffuse, 0.7).lambert_ratio(1.0) == 1.0);
    // The ratios behind issue 12's measurements (sun at 60° and 79°, roughness 0.5).
    const Receiver half = make_receiver(ReceiverModel::PrincipledDiffuse, 0.5);
    CHECK(half.lambert_ratio(0.5) == Approx(1 - 0.5 / 32 + 0.5 * 1.5 / 32));

    // Oren–Nayar: σ = 0 is Lambert; viewed along n the retro term vanishes
    // (t = L·V − (N·L)(N·V) = 0) and the closure is A cosθ at every angle.
    for (double t : angles) {
        const Vec3 l = dir(t, 1.0);
        CHECK(oren_nayar_closure(n, dir(0.8, 2.0), l, 0.0) == Approx(std::cos(t) / kPi));
        for (double s : {0.3, 1.0}) {
            const double a = 1 / (kPi + (3 * kPi - 4) / 6 * s);
            CHECK(oren_nayar_closure(n, n, l, s) == Approx(a * std::cos(t)).margin(1e-15));
            CHECK(receiver_cosine_factor(make_receiver(ReceiverModel::OrenNayar, s),
                                         std::cos(t)) == Approx(a * std::cos(t)).margin(1e-15));
        }
    }
    // A case with t > 0: v and l mirror-symmetric in azimuth 0 at 60°.
    const double s = 1.0, a = 1 / (kPi + (3 * kPi - 4) / 6 * s), b = s * a;
    CHECK(oren_nayar_closure(n, dir(kPi / 3, 0), dir(kPi / 3, 0), s) ==
          Approx(0.5 * (a + b * (1 - 0.25) / 0.5)));
    // σ is clamped to [0, 1] as Cycles' setup does.
    CHECK(make_receiver(ReceiverModel::OrenNayar, 3.0).lambert_ratio(0.5) ==
          make_receiver(ReceiverModel::OrenNayar, 1.0).lambert_ratio(0.5));
    CHECK(make_receiver(ReceiverModel::OrenNayar, 0.0).is_lambert());
    CHECK_THROWS_WITH(make_receiver(ReceiverModel::PrincipledDiffuse, -1), Contains("roughness"));
    CHECK_THROWS_WITH(make_receiver(ReceiverModel::OrenNayar, NAN), Contains("roughness"));
}

TEST_CASE("a receiver's hemisphere integral is its closure's", "[receiver]") {
    // ∫_H cosθ/π·ratio dω = 2 ∫₀¹ c·ratio(c) dc by the midpoint rule (10⁵
    // steps: an error ~1e-10 for these polynomials in c, far below 1e-7).
    for (const Receiver& r :
         {make_receiver(ReceiverModel::Lambert, 0), make_receiver(ReceiverModel::PrincipledDiffuse, 0),
          make_receiver(ReceiverModel::PrincipledDiffuse, 0.5),
          make_receiver(ReceiverModel::PrincipledDiffuse, 1.0),
          make_receiver(ReceiverModel::OrenNayar, 0.8)}) {
        const int steps = 100000;
        double sum = 0;
        for (int i = 0; i < steps; ++i) {
            const double c = (i + 0.5) / steps;
            sum += 2 * c * r.lambert_ratio(c) / steps;
        }
        INFO(r.name());
        CHECK(r.hemisphere_integral() == Approx(sum).epsilon(1e-7));
    }
}

TEST_CASE("direct lighting with a principled receiver: sun and world", "[receiver]") {
    // A delta sun at 79°: exactly E cosθ/π times the closure's ratio.
    {
        Scene scene;
        const double theta = 79 * kPi / 180;
        scene.add_light(make_sun_light(-dir(theta, 0.4), Vec3(3, 3, 3), 0));
        scene.commit();
        DirectLightingSettings s;
        s.techniques = {*parse_technique("bsdf")};
        s.samples = {1};
        for (double r : {0.0, 0.5, 1.0}) {
            s.receiver = make_receiver(ReceiverModel::PrincipledDiffuse, r);
            const double p[3] = {0, 0, 0}, n[3] = {0, 0, 1};
            double value[3], variance[3];
            direct_lighting(scene, p, n, 1, s, value, variance);
            const double c = std::cos(theta);
            CHECK(value[0] == Approx(3 * burley(r, Vec3(0, 0, 1), Vec3(0, 0, 1), dir(theta, 0)) * c));
        }
    }
    // A constant world L over the hemisphere: 2L ∫₀¹ c·ratio(c) dc =
    // L (1 − 1/42 + r·5/84) (Beta integrals ∫c(1−c)⁵ = 1/42, ∫c²(1−c)⁵ = 1/168).
    // Estimated with MIS; the mean of many points within 4 standard errors.
    Scene scene;
    scene.add_light(make_world_light(Vec3(1, 1, 1)));
    scene.commit();
    DirectLightingSettings s;
    s.techniques = {*parse_technique("bsdf"), *parse_technique("uniform/solid-angle")};
    s.samples = {2, 2};
    s.rounds = 8;
    s.strategy = Strategy::Balance;
    const std::size_t P = 400;
    std::vector<double> pts(3 * P, 0.0), nrm(3 * P, 0.0), value(3 * P), variance(3 * P);
    for (std::size_t i = 0; i < P; ++i) nrm[3 * i + 2] = 1;
    for (double r : {0.0, 1.0}) {
        s.receiver = make_receiver(ReceiverModel::PrincipledDiffuse, r);
        direct_lighting(scene, pts.data(), nrm.data(), P, s, value.data(), variance.data());
        double mean = 0, var = 0;
        for (std::size_t i = 0; i < P; ++i) {
            mean += value[3 * i] / P;
            var += variance[3 * i] / (double(P) * P);
        }
        const double exact = 1 - 1.0 / 42 + r * 5.0 / 84;
        INFO("r " << r << " mean " << mean << " exact " << exact << " σ " << std::sqrt(var));
        CHECK(std::abs(mean - exact) <= 4 * std::sqrt(var));
        CHECK(std::abs(mean - 1.0) > 8 * std::sqrt(var));  // distinguishable from Lambert
    }
}

TEST_CASE("a bake takes its mesh's receiver", "[receiver][bake]") {
    Scene scene;
    const std::vector<Vec3> v = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    const std::vector<std::array<std::uint32_t, 3>> t = {{0, 1, 2}, {0, 2, 3}};
    const std::uint32_t lambert = scene.add_mesh(v, t), rough = scene.add_mesh(v, t);
    const double theta = 75 * kPi / 180;
    scene.add_light(make_sun_light(-dir(theta, 1.0), Vec3(1, 1, 1), 0));
    CHECK_THROWS_WITH(scene.set_mesh_receiver(7, Receiver{}), Contains("mesh"));
    scene.set_mesh_receiver(rough, make_receiver(ReceiverModel::OrenNayar, 1.0));
    scene.commit();
    CHECK_THROWS_WITH(scene.set_mesh_receiver(rough, Receiver{}), Contains("committed"));
    BakeSettings s;
    s.target = BakeTarget::Vertices;
    s.lighting.techniques = {*parse_technique("bsdf")};
    s.lighting.samples = {1};
    const double c = std::cos(theta), a = 1 / (kPi + (3 * kPi - 4) / 6);
    s.mesh = lambert;
    const BakeResult l = bake(scene, s);
    s.mesh = rough;
    const BakeResult o = bake(scene, s);
    for (int i = 0; i < 4; ++i) {
        CHECK(l.value[3 * i] == Approx(c / kPi));
        CHECK(o.value[3 * i] == Approx(a * c));
    }
}
