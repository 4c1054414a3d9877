// The per-point set-up's scratch kept from point to point (issue 9 item 5:
// a small bake's fixed cost): a PointLighting that has shaded other points
// must shade a point exactly as a new one does — no technique, table or
// count of an earlier point may leak into the next. The points alternate
// between texels where every light technique takes part and texels where
// none does (no light reaches them), so a stale technique list or mask shows.
#include <catch2/catch.hpp>

#include <cstring>
#include <string>
#include <vector>

#include "render/direct_lighting.h"
#include "support/emissive_sphere.h"
#include "support/square_footprint.h"

using namespace omis;
using omis::testing::SquareFootprint;

namespace {

// The race's `area` scene's kind: a plain rect and a spread rect (whose reach
// ends inside the floor), plus a narrow spread rect that reaches one corner.
void add_scene(Scene& scene) {
    scene.add_mesh({{-3, -3, 0}, {3, -3, 0}, {3, 3, 0}, {-3, 3, 0}}, {{0, 1, 2}, {0, 2, 3}});
    scene.add_light(make_rect_light(Vec3(-0.75, -0.45, 0.85), Vec3(0, 0.5, 0),
                                    Vec3(0.47, 0, -0.17), Vec3(20, 20, 20), false, kPi));
    scene.add_light(make_rect_light(Vec3(0.1, 0.15, 0.6), Vec3(-0.15, 0.26, 0.0),
                                    Vec3(0.78, 0.45, 0.0), Vec3(40, 40, 40), false, 0.5 * kPi));
    scene.add_light(make_rect_light(Vec3(1.2, 1.2, 0.3), Vec3(0, 0.2, 0), Vec3(0.2, 0, 0),
                                    Vec3(9, 9, 9), false, 0.4));
    scene.commit();
}

bool same_bits(const double* a, const double* b) {
    return std::memcmp(a, b, 3 * sizeof(double)) == 0;
}

// Optimal-direct with one light technique (`light_samples` a round) and, with
// `with_bsdf`, bsdf once a round.
DirectLightingSettings light_and_bsdf(const char* light_technique, int light_samples,
                                      bool with_bsdf, std::uint64_t seed) {
    DirectLightingSettings s;
    s.techniques.push_back(*parse_technique(light_technique));
    s.samples = {light_samples};
    if (with_bsdf) {
        s.techniques.push_back(*parse_technique("bsdf"));
        s.samples.push_back(1);
    }
    s.strategy = Strategy::OptimalDirect;
    s.seed = seed;
    return s;
}

// The passes the region tests run: first round, rounds.
constexpr int kRegionCalls[][2] = {{0, 1}, {1, 3}, {4, 4}, {8, 2}};

// Shades every texel over kRegionCalls' passes with `kept` (a context that
// keeps something between passes) and `redone` (one that makes it again) and
// checks they give the same bits; `also(t)` adds a test's own checks.
template <class AlsoCheck>
void check_passes_alike(PointLighting& kept, PointLighting& redone,
                        const std::vector<SquareFootprint>& texels, const std::string& what,
                        AlsoCheck also) {
    for (const auto& call : kRegionCalls)
        for (std::size_t t = 0; t < texels.size(); ++t) {
            const SquareFootprint& f = texels[t];
            double a[3], a_var[3], b[3], b_var[3];
            kept.shade(t, call[0], call[1], f.centre(), &f, a, a_var);
            redone.shade(t, call[0], call[1], f.centre(), &f, b, b_var);
            INFO(what << ", rounds from " << call[0] << ", texel " << t);
            CHECK(same_bits(a, b));
            CHECK(same_bits(a_var, b_var));
            also(t);
        }
}

}  // namespace

TEST_CASE("set-up reuse: a point shades the same after other points as on its own",
          "[texel_tables]") {
    Scene scene;
    add_scene(scene);
    // Lit texels, one at the spread light's rim, one only its corner reaches,
    // one whose footprint the narrow light reaches at two corners but not
    // its centre, and unlit ones (under the one-sided lights' backs: beyond
    // every reach) between them.
    const std::vector<SquareFootprint> texels = {
        {Vec3(0, 0, 0), 0.02},     {Vec3(-2.9, 2.9, 0), 0.02}, {Vec3(0.5, 0.4, 0), 0.05},
        {Vec3(2.9, -2.9, 0), 0.1}, {Vec3(1.3, 1.3, 0), 0.08},  {Vec3(-2.9, -2.9, 0), 0.02},
        {Vec3(1.5, 1.3, 0), 0.08}, {Vec3(-0.4, -0.3, 0), 0.02},
    };
    // keep_reach: the uniform and power tables made again from the reach the
    // first pass kept (LightingContext::table_reach) instead of by probing.
    for (const char* light_technique : {"uniform/solid-angle", "power/area", "unoccluded/area"})
        for (bool keep_reach : {false, true}) {
            DirectLightingSettings s;
            for (const char* name : {light_technique, "bsdf"})
                s.techniques.push_back(*parse_technique(name));
            s.samples = {1, 1};
            s.strategy = Strategy::OptimalDirect;
            s.seed = 5;
            LightingContext shared(scene, s);
            if (keep_reach) {
                shared.keep_table_reach(texels.size());
                CHECK((shared.table_reach.bytes() > 0) == !shared.keeps_texel_tables);
            }
            PointLighting reused(shared);
            for (int pass = 0; pass < 2; ++pass)  // a first pass, then one from kept tables
                for (std::size_t t = 0; t < texels.size(); ++t) {
                    const SquareFootprint& f = texels[t];
                    const int first_round = pass == 0 ? 0 : 1, rounds = pass == 0 ? 1 : 5;
                    double after[3], after_var[3], alone[3], alone_var[3];
                    reused.shade(t, first_round, rounds, f.centre(), &f, after, after_var);
                    LightingContext own(scene, s);
                    PointLighting fresh(own);
                    fresh.shade(t, first_round, rounds, f.centre(), &f, alone, alone_var);
                    INFO(light_technique << (keep_reach ? ", reach kept" : "") << ", pass " << pass
                                         << ", texel " << t);
                    CHECK(same_bits(after, alone));
                    CHECK(same_bits(after_var, alone_var));
                }
        }
}

TEST_CASE("draw counts kept between passes: a later pass shades as one that counts again",
          "[texel_tables]") {
    // A bake keeps where each texel's table draws stand (LightingContext::
    // keep_draw_counts) so that a later pass continues from there instead of
    // re-counting the earlier rounds' selections. The kept counts must give
    // the bits the re-count gives: after one-round and longer passes, after a
    // probe pass that the next pass replaces (it starts again at round 0),
    // after allocated passes of other counts (DrawnRounds), and for a call
    // that goes back to rounds drawn before (the kept counts are then ahead
    // of it), in every stream.
    Scene scene;
    add_scene(scene);
    const std::vector<SquareFootprint> texels = {
        {Vec3(0, 0, 0), 0.02}, {Vec3(0.5, 0.4, 0), 0.05}, {Vec3(1.3, 1.3, 0), 0.08},
        {Vec3(-2.9, -2.9, 0), 0.02}, {Vec3(-0.4, -0.3, 0), 0.02}};
    struct Call {
        int first_round, rounds;
        bool allocated;  // counts {3, 2} instead of the settings' {1, 1}
    };
    // The probe (round 0) is replaced by [0, 2); then [2, 4), [4, 8), two
    // allocated calls, one of the settings' counts again, and [4, 6) again.
    const std::vector<Call> calls = {{0, 1, false}, {0, 2, false},  {2, 2, false},
                                     {4, 4, false}, {8, 2, true},   {10, 1, true},
                                     {11, 3, false}, {4, 2, false}};
    const int allocated_counts[2] = {3, 2};
    for (const char* light_technique :
         {"uniform/solid-angle", "unoccluded/area", "defensive/solid-angle"})
        for (int streams : {1, 4}) {
            DirectLightingSettings s;
            for (const char* name : {light_technique, "bsdf"})
                s.techniques.push_back(*parse_technique(name));
            s.samples = {1, 1};
            s.strategy = Strategy::OptimalDirect;
            s.streams = streams;
            s.seed = 9;
            LightingContext keeping(scene, s), counting(scene, s);
            keeping.keep_draw_counts(texels.size());
            REQUIRE(keeping.draw_counts.bytes() > 0);
            PointLighting continued(keeping), recounted(counting);
            std::vector<DrawnRounds> earlier;
            for (const Call& call : calls) {
                // The calls before this one's rounds (a call from round 0 replaces the probe).
                while (!earlier.empty() && earlier.back().first_round >= call.first_round)
                    earlier.pop_back();
                const int* counts = call.allocated ? allocated_counts : nullptr;
                for (std::size_t t = 0; t < texels.size(); ++t) {
                    const SquareFootprint& f = texels[t];
                    double a[3], a_var[3], b[3], b_var[3];
                    continued.shade(t, call.first_round, call.rounds, f.centre(), &f, a, a_var,
                                    counts, nullptr, nullptr, &earlier);
                    recounted.shade(t, call.first_round, call.rounds, f.centre(), &f, b, b_var,
                                    counts, nullptr, nullptr, &earlier);
                    INFO(light_technique << ", " << streams << " streams, rounds from "
                                         << call.first_round << ", texel " << t);
                    CHECK(same_bits(a, b));
                    CHECK(same_bits(a_var, b_var));
                }
                earlier.push_back({call.first_round, call.rounds, counts});
            }
        }
}

TEST_CASE("techniques kept between passes where only selectors draw: a later pass shades as "
          "one that chooses them again", "[texel_tables]") {
    // A bake's texels have a slot each in the texel tables (index_points);
    // where no technique draws from a table, the slot keeps which techniques
    // take part (the tree's reach over the texel) instead of nothing. A later
    // pass from it must give the bits of one that chooses them again, at lit
    // and unlit texels (unlit: the tree drops out, or with it alone nothing
    // takes part), and with shadowed texels' draws (shadowed_draws).
    Scene scene;
    add_scene(scene);
    const std::vector<SquareFootprint> texels = {
        {Vec3(0, 0, 0), 0.02}, {Vec3(-2.9, 2.9, 0), 0.02}, {Vec3(0.5, 0.4, 0), 0.05},
        {Vec3(1.3, 1.3, 0), 0.08}, {Vec3(-2.9, -2.9, 0), 0.02}, {Vec3(-0.4, -0.3, 0), 0.02}};
    for (bool with_bsdf : {false, true})
        for (int shadowed_draws : {1, 4}) {
            DirectLightingSettings s = light_and_bsdf("tree/solid-angle", 1, with_bsdf, 17);
            s.shadowed_draws = shadowed_draws;
            LightingContext keeping(scene, s), choosing(scene, s);
            keeping.texel_tables.index_points(texels.size());
            keeping.keep_shadow_verdicts(texels.size());
            choosing.keep_shadow_verdicts(texels.size());
            PointLighting kept(keeping), chosen(choosing);
            check_passes_alike(kept, chosen, texels,
                               std::string(with_bsdf ? "tree + bsdf" : "tree") + ", " +
                                   std::to_string(shadowed_draws) + " draws shadowed",
                               [](std::size_t) {});
            // Every texel kept its techniques in its slot; without slots
            // (the map) nothing is kept where no table was made.
            CHECK(keeping.texel_tables.size() == texels.size());
            CHECK(choosing.texel_tables.size() == 0);
        }
}

TEST_CASE("region radii kept between passes: a later pass shades as one that places the "
          "corners again", "[texel_tables]") {
    // A bake keeps each texel's region radius (LightingContext::
    // keep_region_radii: its footprint's farthest corner from the centre),
    // with which selectors draw for every sample of the texel. A later pass
    // that takes it from there must give the bits of one that places the
    // corners again, for the tree drawn by solid angle and by area, with and
    // without `bsdf`.
    Scene scene;
    add_scene(scene);
    const std::vector<SquareFootprint> texels = {
        {Vec3(0, 0, 0), 0.02}, {Vec3(0.5, 0.4, 0), 0.05}, {Vec3(1.3, 1.3, 0), 0.08},
        {Vec3(-2.9, -2.9, 0), 0.02}, {Vec3(-0.4, -0.3, 0), 0.02}};
    for (const char* light_technique : {"tree/solid-angle", "tree/area"})
        for (bool with_bsdf : {false, true}) {
            const DirectLightingSettings s = light_and_bsdf(light_technique, 1, with_bsdf, 13);
            LightingContext keeping(scene, s), placing(scene, s);
            keeping.keep_region_radii(texels.size());
            REQUIRE(keeping.region_radii.size() == texels.size());
            PointLighting kept(keeping), placed(placing);
            check_passes_alike(kept, placed, texels,
                               std::string(light_technique) + (with_bsdf ? " + bsdf" : ""),
                               [&](std::size_t t) { CHECK(keeping.region_radii[t] > 0); });
        }
}

TEST_CASE("region branching kept between passes: a later pass shades as one that walks the "
          "tree again", "[texel_tables]") {
    // A bake keeps the light tree's branching at each texel's region
    // (LightingContext::keep_region_branching) and starts a later pass's
    // walks from it. The later passes must give the bits of passes that
    // evaluate every node again: with room for the nodes walked (16 a texel)
    // and with a store that fills up (2), for the tree drawn by solid angle
    // and by area, with and without `bsdf`. The race's emissive_mesh kind:
    // an emissive sphere of 2208 triangles over the floor, and a rect.
    Scene scene;
    scene.add_mesh({{-3, -3, 0}, {3, -3, 0}, {3, 3, 0}, {-3, 3, 0}}, {{0, 1, 2}, {0, 2, 3}});
    testing::add_emissive_sphere(scene, Vec3(0.2, 0.1, 0.6), 0.3, 24, 48, Vec3(3, 3, 3));
    scene.set_mesh_lights(false);  // a light tree over its triangles
    scene.add_light(make_rect_light(Vec3(0.2, 0.05, 1.4), Vec3(0, 0.3, 0), Vec3(0.3, 0, 0),
                                    Vec3(40, 40, 40), false, kPi));
    scene.commit();
    const std::vector<SquareFootprint> texels = {
        {Vec3(0, 0, 0), 0.01}, {Vec3(0.5, 0.4, 0), 0.03}, {Vec3(1.3, 1.3, 0), 0.08},
        {Vec3(-2.9, -2.9, 0), 0.02}, {Vec3(0.2, 0.1, 0), 0.005}};
    constexpr std::uint32_t node_mask = (1u << LightSelector::KeptNode::kClusterShift) - 1;
    for (const char* light_technique : {"tree/solid-angle", "tree/area"})
        for (bool with_bsdf : {false, true})
            for (std::size_t max_nodes : {2, 16}) {
                const DirectLightingSettings s =
                    light_and_bsdf(light_technique, 2, with_bsdf, 7);
                LightingContext keeping(scene, s), walking(scene, s);
                keeping.keep_region_radii(texels.size());
                keeping.keep_region_branching(texels.size(), max_nodes);
                walking.keep_region_radii(texels.size());
                REQUIRE(keeping.region_nodes == max_nodes);
                PointLighting kept(keeping), walked(walking);
                const std::string what = std::string(light_technique) +
                                         (with_bsdf ? " + bsdf" : "") + ", " +
                                         std::to_string(max_nodes) + " nodes";
                check_passes_alike(kept, walked, texels, what, [&](std::size_t t) {
                    // Every texel here sees the sphere: its walks began at
                    // the root, which its store holds first.
                    const LightSelector::KeptNode* store = keeping.region_branching_of(t);
                    REQUIRE(store);
                    CHECK((store[0].node_and_clusters & node_mask) == 0);
                    if (max_nodes == 2)
                        CHECK(store[1].node_and_clusters != LightSelector::KeptNode::kNone);
                });
            }
}

TEST_CASE("region branching's block is handed on to the next context, emptied", "[texel_tables]") {
    // A bake's kept branching (up to 6 MiB) goes to the next context instead
    // of back to the allocator, whose fresh pages cost a 0.05 s bake 15-17 ms
    // of page faults in Blender. The next context must get the same block
    // with every node empty again, whatever the last one wrote there.
    Scene scene;
    scene.add_mesh({{-3, -3, 0}, {3, -3, 0}, {3, 3, 0}, {-3, 3, 0}}, {{0, 1, 2}, {0, 2, 3}});
    testing::add_emissive_sphere(scene, Vec3(0.2, 0.1, 0.6), 0.3, 12, 24, Vec3(3, 3, 3));
    scene.set_mesh_lights(false);  // a light tree over its triangles
    scene.commit();
    const DirectLightingSettings s = light_and_bsdf("tree/solid-angle", 2, false, 7);
    constexpr std::size_t points = 4096;
    const LightSelector::KeptNode* block = nullptr;
    {
        LightingContext first(scene, s);
        first.keep_region_branching(points);
        REQUIRE(first.region_nodes == LightingContext::kMaxRegionNodes);
        for (LightSelector::KeptNode& node : first.region_branching) {
            node.node_and_clusters = 7;
            node.importance[2] = 1.5f;
        }
        block = first.region_branching.data();
    }
    // A block of the same size asked for meanwhile: where the context had
    // freed its block, the allocator would hand it out here.
    std::vector<LightSelector::KeptNode> meanwhile(points * LightingContext::kMaxRegionNodes);
    LightingContext next(scene, s);
    next.keep_region_branching(points / 2);
    CHECK(next.region_branching.data() == block);
    REQUIRE(next.region_branching.size() == points / 2 * next.region_nodes);
    std::size_t stale = 0;
    for (const LightSelector::KeptNode& node : next.region_branching)
        stale += node.node_and_clusters != LightSelector::KeptNode::kNone ||
                 node.importance[2] != 0.0f;
    CHECK(stale == 0);
}
