// A point whose only technique draws lights estimates each drawn light's own
// part, f_l / (P(l) p_l(ω)) (direct_lighting.cpp, take_sample): lights that
// overlap along a direction must still add (SPEC §3), and an occluder must
// hide each of them up to its own depth.
//
// As in test_direct_lighting.cpp: T copies of one receiver in one call are T
// independent estimates; their mean must lie within 4 standard errors
// (measured from the copies) of the exact answer, a 6e-5 miss probability for
// a normal mean; the seeds are fixed.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "render/direct_lighting.h"
#include "sampling/irradiance.h"
#include "support/lighting_settings.h"
#include "support/point_copies.h"

using namespace omis;

namespace {

constexpr double kSigmas = 4.0;
constexpr int kCopies = 64;

// A one-sided square light facing down (−z), centred over the origin.
Light ceiling_square(double size, double height, double radiance) {
    return make_rect_light(Vec3(-size / 2, -size / 2, height), Vec3(0, size, 0),
                           Vec3(size, 0, 0), Vec3(radiance, radiance, radiance), false, kPi);
}

// E/π at x (normal +z) from the part x0 ≤ x ≤ x1, |y| ≤ half of a light at z.
double strip_value(const Vec3& x, double x0, double x1, double half, double z, double radiance) {
    return radiance *
           polygon_irradiance(x, Vec3(0, 0, 1),
                              {{x0, -half, z}, {x1, -half, z}, {x1, half, z}, {x0, half, z}}) /
           kPi;
}

}  // namespace

TEST_CASE("one light technique: stacked lights add, each shadowed up to its own depth",
          "[direct][own_light]") {
    // A 1 m square at 1 m in front of a 2 m square at 2 m: every direction
    // toward the small one also meets the large one.
    const Vec3 x(-0.1, 0, 0), up(0, 0, 1);
    for (bool occluded : {false, true}) {
        Scene scene;
        scene.add_light(ceiling_square(1.0, 1.0, 1.0));
        scene.add_light(ceiling_square(2.0, 2.0, 3.0));
        // An opaque half-plane x ≥ 0 at z = 0.5: from x the small light is
        // hidden beyond x = 0.1, the large one beyond x = 0.3 (the ray from
        // (−0.1, 0, 0) to (b, y, 2) crosses z = 0.5 at x = −0.1 + (b + 0.1)/4).
        if (occluded)
            scene.add_mesh(
                std::vector<Vec3>{{0, -50, 0.5}, {50, -50, 0.5}, {50, 50, 0.5}, {0, 50, 0.5}},
                {{0, 1, 2}, {0, 2, 3}});
        scene.commit();
        const double exact = occluded ? strip_value(x, -0.5, 0.1, 0.5, 1.0, 1.0) +
                                            strip_value(x, -1.0, 0.3, 1.0, 2.0, 3.0)
                                      : strip_value(x, -0.5, 0.5, 0.5, 1.0, 1.0) +
                                            strip_value(x, -1.0, 1.0, 1.0, 2.0, 3.0);
        for (const char* technique : {"uniform/solid-angle", "power/area"})
            for (Strategy s : {Strategy::Balance, Strategy::OptimalDirect}) {
                const testing::PointCopies e = testing::light_point_copies(
                    scene, x, up, testing::lighting_settings({technique}, {8}, 4, s, 3), kCopies);
                INFO(technique << ", " << strategy_name(s) << (occluded ? ", occluded" : ""));
                CHECK(e.finite);
                CHECK(std::abs(e.mean - exact) <= kSigmas * e.standard_error);
                // Each sample traces one occlusion ray toward its own light
                // (none without geometry), and evaluates no other density.
                CHECK(e.stats.rays_traced == (occluded ? e.stats.samples : 0));
                CHECK(e.stats.pdf_evaluations == 0);
            }
    }
}
