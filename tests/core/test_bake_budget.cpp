// Small bakes' fixed cost (issue 9 items 4–5): under a time budget the first
// pass is one round for every strategy, and a scene's light selectors are
// built once and shared by its bakes.
#include <catch2/catch.hpp>

#include <vector>

#include "bake/bake.h"
#include "render/scene.h"
#include "render/techniques.h"
#include "support/floor_lambert.h"

using namespace omis;

using testing::two_triangle_floor;

namespace {

// Two light techniques (a round: 5 samples) and the optimal strategy over a
// 16² lightmap: `samples` per texel under `time_budget`.
BakeSettings optimal_budget(long long samples, double time_budget) {
    BakeSettings s;
    s.lighting.techniques = {*parse_technique("uniform/solid-angle"),
                             *parse_technique("uniform/area")};
    s.lighting.samples = {2, 3};
    s.lighting.strategy = Strategy::OptimalDirect;
    s.samples = samples;
    s.time_budget = time_budget;
    s.width = s.height = 16;
    return s;
}

}  // namespace

TEST_CASE("a time budget's first pass is one round, whatever the strategy", "[bake]") {
    Scene scene;
    std::vector<float> positions, uvs;
    std::vector<std::uint32_t> triangles;
    two_triangle_floor(scene, positions, triangles, uvs);
    for (Strategy strategy :
         {Strategy::Balance, Strategy::OptimalDirect, Strategy::OptimalProgressive}) {
        BakeSettings s;
        s.lighting.techniques = {*parse_technique("uniform/solid-angle"),
                                 *parse_technique("uniform/area")};
        s.lighting.samples = {2, 3};  // one round: 5 samples
        s.lighting.rounds = 1 << 20;
        s.lighting.strategy = strategy;
        s.width = s.height = 16;
        s.time_budget = 1e-9;  // spent before the first pass ends: it alone runs
        const BakeResult r = bake(scene, s);
        INFO("strategy " << int(strategy));
        CHECK(r.stats.status == BakeStatus::TimeBudget);
        CHECK(r.stats.passes == 1);
        REQUIRE(r.stats.covered == 16u * 16u);
        for (std::size_t i = 0; i < r.samples.size(); ++i)
            if (r.mask[i] > 0) CHECK(r.samples[i] == 5u);
    }
}

TEST_CASE("an optimal strategy's probe pass is replaced: samples = N still takes exactly N",
          "[bake]") {
    // One round; two and a final 2; four rounds; eight.
    for (long long n : {5LL, 12LL, 20LL, 40LL}) {
        // A scene of its own: no earlier bake has measured what a pass costs,
        // so the first pass is the one-round probe.
        Scene scene;
        std::vector<float> positions, uvs;
        std::vector<std::uint32_t> triangles;
        two_triangle_floor(scene, positions, triangles, uvs);
        const BakeSettings s = optimal_budget(n, 1000);  // passes (a probe first), never reached
        const BakeResult r = bake(scene, s);
        INFO("samples " << n);
        CHECK(r.stats.status == BakeStatus::Complete);
        CHECK(r.stats.passes >= (n > 5 ? 2 : 1));
        CHECK(r.stats.samples == std::uint64_t(n) * r.stats.covered);
        for (std::size_t i = 0; i < r.samples.size(); ++i)
            if (r.mask[i] > 0) CHECK(r.samples[i] == std::uint32_t(n));
        if (n == 20) {
            // The pass that replaces the probe draws rounds 0–3 again, all of
            // them (4× the probe; the budget is far off): the values of a
            // bake in one pass.
            BakeSettings whole = s;
            whole.time_budget = 0;
            CHECK(r.stats.passes == 2);
            CHECK(r.value == bake(scene, whole).value);
        }
    }
}

TEST_CASE("a time budget's first pass takes the rounds an earlier bake of its shape measured "
          "to fit", "[bake]") {
    Scene scene;
    std::vector<float> positions, uvs;
    std::vector<std::uint32_t> triangles;
    two_triangle_floor(scene, positions, triangles, uvs);
    const BakeSettings s = optimal_budget(40, 1000);  // eight rounds; all fit, by any measure
    BakeSettings whole = s;
    whole.time_budget = 0;

    // Nothing measured yet: a one-round probe, then the passes after it.
    const BakeResult first = bake(scene, s);
    CHECK(first.stats.passes >= 2);
    // The same shape again: its eight rounds fit in one pass by the first
    // bake's measure, and that pass is the bake of all rounds at once.
    const BakeResult again = bake(scene, s);
    CHECK(again.stats.passes == 1);
    CHECK(again.stats.samples == 40u * again.stats.covered);
    CHECK(again.value == bake(scene, whole).value);
    // Another shape (the lightmap's size) has nothing measured: a probe again.
    BakeSettings larger = s;
    larger.width = larger.height = 20;
    CHECK(bake(scene, larger).stats.passes >= 2);
    // A budget spent before the first pass: one round, measured or not.
    BakeSettings spent = s;
    spent.time_budget = 1e-9;
    const BakeResult one = bake(scene, spent);
    CHECK(one.stats.passes == 1);
    CHECK(one.stats.samples == 5u * one.stats.covered);
}

TEST_CASE("a scene keeps the last pass cost of each bake shape, and a bounded number of them",
          "[bake]") {
    Scene scene;
    CHECK_FALSE(scene.measured_pass_cost(7));
    scene.remember_pass_cost(7, {0.01, 0.002, 4});
    scene.remember_pass_cost(7, {0.02, 0.003, 1});  // the last bake's measure wins
    REQUIRE(scene.measured_pass_cost(7));
    CHECK(scene.measured_pass_cost(7)->first_pass_fixed == 0.02);
    CHECK(scene.measured_pass_cost(7)->round == 0.003);
    // Thousands of shapes (a script baking every size) do not pile up: once
    // the store is full it starts again.
    for (std::uint64_t shape = 100; shape < 100 + 10000; ++shape)
        scene.remember_pass_cost(shape, {0, 1, 1});
    std::size_t kept = 0;
    for (std::uint64_t shape = 100; shape < 100 + 10000; ++shape)
        kept += bool(scene.measured_pass_cost(shape));
    CHECK(kept > 0);
    CHECK(kept <= 256);
    CHECK(scene.measured_pass_cost(100 + 9999));  // the newest stays
}

TEST_CASE("a scene builds each light selector once, as LightSelector would", "[bake]") {
    Scene lit;  // 40 triangle lights, every other one two-sided
    std::vector<std::uint32_t> integrated;
    for (int k = 0; k < 40; ++k) {
        const double x = -1 + 0.05 * k;
        lit.add_light(make_triangle_light(Vec3(x, 0, 1), Vec3(x + 0.04, 0, 1),
                                          Vec3(x, 0.1 * (1 + k % 3), 1.2), Vec3(1, 1, 1),
                                          k % 2 == 0));
        integrated.push_back(std::uint32_t(k));
    }
    lit.commit();
    for (auto kind : {LightSelector::Kind::Uniform, LightSelector::Kind::Power,
                      LightSelector::Kind::Tree}) {
        const LightSelector& kept = lit.light_selector(kind, false);
        CHECK(&kept == &lit.light_selector(kind, false));  // built once
        const LightSelector built(kind, lit.lights(), integrated, lit.bounding_radius());
        REQUIRE(kept.size() == built.size());
        for (double y : {-0.7, 0.0, 0.4})
            for (std::uint32_t l : integrated)
                CHECK(kept.pmf(Vec3(0.3, y, 0), Vec3(0, 0, 1), l) ==
                      built.pmf(Vec3(0.3, y, 0), Vec3(0, 0, 1), l));
    }
    CHECK(lit.light_selector(LightSelector::Kind::Tree, true).empty());  // no delta lights
    Scene uncommitted;
    CHECK_THROWS_AS(uncommitted.light_selector(LightSelector::Kind::Tree, false),
                    std::logic_error);
}
