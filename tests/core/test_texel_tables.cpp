// Texel tables kept from pass to pass (render/texel_tables.h): a bake's later
// pass must shade a texel exactly as if it had worked out the texel's
// techniques and light tables anew, and the store must keep to its budget.
#include <catch2/catch.hpp>

#include <array>
#include <cstring>
#include <vector>

#include "render/direct_lighting.h"
#include "support/square_footprint.h"

using namespace omis;
using omis::testing::SquareFootprint;

namespace {

// area_round's lights and more: a spread disk, a plain ellipse, a spread
// rect whose reach ends inside the floor, above a 4 m floor.
void add_spread_scene(Scene& scene) {
    scene.add_mesh({{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}}, {{0, 1, 2}, {0, 2, 3}});
    const Vec3 down_a = normalize(Vec3(0, 1, -0.5)) * 0.3, side = Vec3(0.3, 0, 0);
    scene.add_light(make_ellipse_light(Vec3(0, -0.4, 0.7), down_a, side, Vec3(4, 4, 4), false,
                                       2.1));
    scene.add_light(make_ellipse_light(Vec3(0.3, 0.5, 0.5), Vec3(0, 0.15, 0), Vec3(0.3, 0, 0),
                                       Vec3(3, 2, 1), false, kPi));
    scene.add_light(make_rect_light(Vec3(-0.9, 0.2, 0.4), Vec3(0, 0.4, 0), Vec3(0.4, 0, 0),
                                    Vec3(5, 5, 5), false, 0.6));
    scene.commit();
}

DirectLightingSettings settings_with(Strategy strategy) {
    DirectLightingSettings s;
    for (const char* name : {"unoccluded/solid-angle", "power/solid-angle", "bsdf"})
        s.techniques.push_back(*parse_technique(name));
    s.samples = {1, 1, 1};
    s.strategy = strategy;
    s.seed = 11;
    return s;
}

bool same_bits(const double* a, const double* b) { return std::memcmp(a, b, 3 * sizeof(double)) == 0; }

}  // namespace

TEST_CASE("texel tables: a later pass from kept tables equals one that works them out",
          "[texel_tables]") {
    Scene scene;
    add_spread_scene(scene);
    // Texels under each light, at the rim of the spread rect's reach, and
    // where no light reaches the centre but some reach a corner.
    const std::vector<SquareFootprint> texels = {
        {Vec3(0, -0.4, 0), 0.02},   {Vec3(0.3, 0.5, 0), 0.02}, {Vec3(-0.7, 0.4, 0), 0.02},
        {Vec3(-0.3, 0.9, 0), 0.05}, {Vec3(1.5, -1.5, 0), 0.1}, {Vec3(-1.9, 1.9, 0), 0.08},
    };
    for (Strategy strategy : {Strategy::Balance, Strategy::OptimalDirect}) {
        const DirectLightingSettings s = settings_with(strategy);
        LightingContext kept(scene, s), fresh(scene, s);
        PointLighting passes(kept), once(fresh);
        for (std::size_t t = 0; t < texels.size(); ++t) {
            const SquareFootprint& f = texels[t];
            double first[3], later[3], later_var[3], direct[3], direct_var[3];
            passes.shade(t, 0, 1, f.centre(), &f, first, nullptr);  // keeps its tables
            passes.shade(t, 1, 6, f.centre(), &f, later, later_var);  // takes them back
            once.shade(t, 1, 6, f.centre(), &f, direct, direct_var);  // works them out
            INFO("texel " << t << ", strategy " << int(strategy));
            CHECK(same_bits(later, direct));
            CHECK(same_bits(later_var, direct_var));
        }
        CHECK(kept.texel_tables.size() == texels.size());
    }
}

TEST_CASE("texel tables: tables that need no irradiance are made again, not kept",
          "[texel_tables]") {
    // `uniform` and `power` tables hold only which lights reach the probes:
    // cheaper to make at every pass than to keep (direct_lighting.cpp,
    // cheap_tables_). A later pass still equals one that works them out, and
    // with an `unoccluded` technique beside them the tables are kept.
    Scene scene;
    add_spread_scene(scene);
    const SquareFootprint f(Vec3(-0.3, 0.9, 0), 0.05);
    for (const char* light : {"uniform/solid-angle", "power/area", "unoccluded/solid-angle"}) {
        DirectLightingSettings s;
        for (const char* name : {light, "bsdf"}) s.techniques.push_back(*parse_technique(name));
        s.samples = {1, 1};
        s.seed = 5;
        LightingContext kept(scene, s), fresh(scene, s);
        PointLighting passes(kept), once(fresh);
        double first[3], later[3], direct[3];
        passes.shade(0, 0, 1, f.centre(), &f, first, nullptr);
        passes.shade(0, 1, 4, f.centre(), &f, later, nullptr);
        once.shade(0, 1, 4, f.centre(), &f, direct, nullptr);
        INFO(light);
        CHECK(same_bits(later, direct));
        CHECK(kept.texel_tables.size() == (std::strcmp(light, "unoccluded/solid-angle") == 0 ? 1u : 0u));
    }
}

TEST_CASE("texel tables: set-up timing counts the kept tables' set-up and the rounds' "
          "sampling, only while on", "[texel_tables]") {
    Scene scene;
    add_spread_scene(scene);
    const LightingContext context(scene, settings_with(Strategy::Balance));
    PointLighting shader(context);
    const SquareFootprint f(Vec3(0, -0.4, 0), 0.02);
    double v[3];
    shader.shade(0, 0, 1, f.centre(), &f, v, nullptr);  // off: nothing timed
    CHECK(shader.setup_timing.shading == 0);
    CHECK(shader.setup_timing.kept_setup == 0);
    CHECK(shader.setup_timing.rounds == 0);
    shader.setup_timing.on = true;
    shader.shade(1, 0, 1, f.centre(), &f, v, nullptr);  // keeps its tables: set-up timed
    const PointLighting::SetupTiming first = shader.setup_timing;
    CHECK(first.kept_setup > 0);
    CHECK(first.rounds > 0);
    // Set-up and sampling are disjoint parts of the shading.
    CHECK(first.kept_setup + first.rounds <= first.shading);
    shader.shade(1, 1, 1, f.centre(), &f, v, nullptr);  // takes them back: shading only
    CHECK(shader.setup_timing.kept_setup == first.kept_setup);
    CHECK(shader.setup_timing.shading > first.shading);
    CHECK(shader.setup_timing.rounds > first.rounds);
}

TEST_CASE("texel tables: points without a footprint keep nothing at their first pass",
          "[texel_tables]") {
    Scene scene;
    add_spread_scene(scene);
    const LightingContext context(scene, settings_with(Strategy::Balance));
    PointLighting shader(context);
    double v[3];
    shader.shade(0, 0, 2, Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(0, 0, 1), v, nullptr);
    CHECK(context.texel_tables.size() == 0);  // direct_lighting: one call per point
    shader.shade(0, 2, 2, Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(0, 0, 1), v, nullptr);
    CHECK(context.texel_tables.size() == 1);  // a bake's vertex, at its second pass
}

TEST_CASE("texel tables: the store keeps to its byte budget", "[texel_tables]") {
    auto entry = [] {
        TexelTables::Entry e;
        e.mask = 3;
        e.tables.push_back({0, {0, 1, 2}, {0.5, 0.25, 0.25}});
        return e;
    };
    TexelTables probe;
    probe.keep(0, entry());
    const std::size_t one = probe.bytes();
    REQUIRE(one > 0);

    TexelTables store(3 * one);
    for (std::uint64_t t = 0; t < 5; ++t) store.keep(t, entry());
    CHECK(store.size() == 3);
    CHECK(store.bytes() == 3 * one);
    REQUIRE(store.find(1) != nullptr);
    CHECK(store.find(1)->tables[0].probability[1] == 0.25);
    CHECK(store.find(4) == nullptr);  // past the budget: recomputed instead

    TexelTables again(10 * one);
    again.keep(7, entry());
    again.keep(7, entry());  // kept already: neither replaced nor counted twice
    CHECK(again.size() == 1);
    CHECK(again.bytes() == one);
}

TEST_CASE("texel tables: indexed points keep, find and budget as the map does",
          "[texel_tables]") {
    TexelTables::Entry e;
    e.mask = 5;
    e.tables.push_back({2, {0, 1}, {0.75, 0.25}});
    TexelTables store;
    store.index_points(10);
    const std::size_t empty = store.bytes();
    CHECK(store.find(3) == nullptr);
    TexelTables::Entry copy = e;
    store.keep(3, std::move(copy));
    REQUIRE(store.find(3) != nullptr);
    CHECK(store.find(3)->mask == 5);
    CHECK(store.find(3)->tables[0].probability[0] == 0.75);
    CHECK(store.bytes() > empty);
    const std::size_t one = store.bytes();
    copy = e;
    store.keep(3, std::move(copy));  // kept already
    CHECK(store.bytes() == one);
    copy = e;
    store.keep(12, std::move(copy));  // past the indexed points: the map
    CHECK(store.find(12) != nullptr);
    CHECK(store.size() == 2);
}

namespace {

// A SquareFootprint whose light tables are weighed at a shared anchor.
class AnchoredFootprint : public SquareFootprint {
public:
    AnchoredFootprint(const Vec3& centre, double half, std::uint64_t id, const Vec3& anchor)
        : SquareFootprint(centre, half), id_(id), anchor_(anchor) {}
    bool table_anchor(Anchor& a) const override {
        a.id = id_;
        a.at = SurfacePoint{anchor_, Vec3(0, 0, 1), Vec3(0, 0, 1)};
        return true;
    }

private:
    std::uint64_t id_;
    Vec3 anchor_;
};

}  // namespace

// Footprint::table_anchor: a texel's `unoccluded` weights come from its
// anchor, whichever texels were shaded before it (the weights kept per
// thread for recent anchors must never leak into another anchor's texels).
TEST_CASE("texel tables: anchored weights depend on the anchor, not on the order of texels",
          "[texel_tables]") {
    Scene scene;
    add_spread_scene(scene);
    const DirectLightingSettings s = settings_with(Strategy::OptimalDirect);
    // Two anchors under the spread disk and one under the ellipse; the
    // texels of each, and a texel whose anchor no light reaches the same
    // way (the rim of the spread rect's reach).
    const Vec3 a0(0, -0.4, 0), a1(0.3, 0.5, 0), a2(-0.7, 0.4, 0);
    const std::vector<AnchoredFootprint> texels = {
        {Vec3(0.02, -0.38, 0), 0.01, 0, a0}, {Vec3(0.05, -0.42, 0), 0.01, 0, a0},
        {Vec3(0.32, 0.52, 0), 0.01, 1, a1},  {Vec3(0.27, 0.47, 0), 0.01, 1, a1},
        {Vec3(-0.66, 0.44, 0), 0.01, 2, a2}, {Vec3(-0.3, 0.9, 0), 0.05, 2, a2},
    };
    // Each texel alone (a fresh shader: nothing kept from another texel),
    // against all texels in a row through one shader, forward and backward.
    std::vector<std::array<double, 3>> alone(texels.size());
    for (std::size_t t = 0; t < texels.size(); ++t) {
        LightingContext context(scene, s);
        PointLighting shader(context);
        shader.shade(t, 0, 4, texels[t].centre(), &texels[t], alone[t].data(), nullptr);
    }
    for (bool backward : {false, true}) {
        LightingContext context(scene, s);
        PointLighting shader(context);
        for (std::size_t j = 0; j < texels.size(); ++j) {
            const std::size_t t = backward ? texels.size() - 1 - j : j;
            double v[3];
            shader.shade(t, 0, 4, texels[t].centre(), &texels[t], v, nullptr);
            INFO("texel " << t << (backward ? " (backward)" : " (forward)"));
            CHECK(same_bits(v, alone[t].data()));
        }
    }
    // The anchor is what the weights come from: the same texel under another
    // anchor gets another table (values differ), under no anchor too.
    // Same stream (the same draws), fresh contexts: only the table differs.
    const SquareFootprint plain(Vec3(0.02, -0.38, 0), 0.01);
    const AnchoredFootprint moved(Vec3(0.02, -0.38, 0), 0.01, 7, Vec3(0.4, -0.9, 0));
    double v_plain[3], v_moved[3];
    LightingContext c_plain(scene, s), c_moved(scene, s);
    PointLighting(c_plain).shade(0, 0, 4, plain.centre(), &plain, v_plain, nullptr);
    PointLighting(c_moved).shade(0, 0, 4, moved.centre(), &moved, v_moved, nullptr);
    CHECK_FALSE(same_bits(v_plain, alone[0].data()));
    CHECK_FALSE(same_bits(v_moved, alone[0].data()));
    CHECK_FALSE(same_bits(v_moved, v_plain));
}
