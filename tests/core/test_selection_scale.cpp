// The light tree among many lights (render/light_selection.h): its pmfs sum
// to 1 wherever it can draw, and match how often each light is drawn.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "math/random.h"
#include "render/light_selection.h"
#include "sampler_check.h"

using namespace omis;

namespace {

Vec3 random_direction(Pcg32& rng) {
    const double z = 1 - 2 * rng.next_double(), phi = 2 * kPi * rng.next_double();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}

// Small one-sided rects, triangles and spots facing every way in a 4 m cube,
// powers over four decades: many tree nodes whose looser bounds reach a point
// that neither child's bounds do.
std::vector<Light> scattered_lights(int count, bool with_unbounded) {
    Pcg32 rng(21, 4);
    std::vector<Light> lights;
    for (int i = 0; i < count; ++i) {
        const Vec3 c(4 * rng.next_double() - 2, 4 * rng.next_double() - 2,
                     4 * rng.next_double() - 2);
        const Vec3 radiance = Vec3(1, 1, 1) * std::pow(10.0, 4 * rng.next_double() - 2);
        const Frame f(random_direction(rng));
        const double size = 0.02 + 0.1 * rng.next_double();
        switch (i % 3) {
            case 0:
                lights.push_back(make_rect_light(c, f.to_world(Vec3(size, 0, 0)),
                                                 f.to_world(Vec3(0, size, 0)), radiance, false,
                                                 i % 2 ? kPi : 0.8));
                break;
            case 1:
                lights.push_back(make_triangle_light(c, c + f.to_world(Vec3(size, 0, 0)),
                                                     c + f.to_world(Vec3(0, size, 0)), radiance,
                                                     false));
                break;
            default:
                lights.push_back(make_spot_light(c, f.to_world(Vec3(0, 0, 1)), radiance, 0.01,
                                                 0.6, 0.1));
        }
    }
    if (with_unbounded) {
        lights.push_back(make_sun_light(Vec3(0, 0.3, -1), Vec3(1, 1, 1), 0.1));
        lights.push_back(make_world_light(Vec3(1, 1, 1) * 0.1));
    }
    return lights;
}

std::vector<std::uint32_t> all_ids(std::size_t n) {
    std::vector<std::uint32_t> ids(n);
    for (std::size_t i = 0; i < n; ++i) ids[i] = std::uint32_t(i);
    return ids;
}

// p-value of Pearson's chi-square of N draws against the pmfs (the shared
// checker's: lights expected < 5 times pooled); a light of pmf 0 is never drawn.
double draws_pvalue(const LightSelector& s, const LightSelector::Receiver& at,
                    const std::vector<double>& pmf, int N, Pcg32& rng) {
    std::vector<double> count(pmf.size()), expected(pmf.size());
    for (int i = 0; i < N; ++i) {
        const auto pick = s.sample(at, rng.next_double());
        REQUIRE(pick);  // every draw ends at a light
        REQUIRE(pick->pmf == Approx(pmf[pick->light]).epsilon(1e-12));
        count[pick->light] += 1;
    }
    for (std::size_t l = 0; l < pmf.size(); ++l) {
        expected[l] = N * pmf[l];
        if (pmf[l] == 0) REQUIRE(count[l] == 0);
    }
    return testing::chi_square_pvalue(count, expected);
}

}  // namespace

TEST_CASE("light tree pmfs sum to 1 and match drawing frequencies among many lights",
          "[selection]") {
    for (bool with_unbounded : {false, true}) {
        const std::vector<Light> lights = scattered_lights(3000, with_unbounded);
        const LightSelector s(LightSelector::Kind::Tree, lights, all_ids(lights.size()), 10.0);
        Pcg32 rng(5, 9);
        int reached = 0, checked_draws = 0;
        for (int p = 0; p < 200; ++p) {
            // Points inside and around the cloud of lights.
            const Vec3 x(6 * rng.next_double() - 3, 6 * rng.next_double() - 3,
                         6 * rng.next_double() - 3);
            const Vec3 n = random_direction(rng);
            // The pmfs through a memo, the draws without: they must agree.
            LightSelector::Memo memo;
            std::vector<double> pmf(lights.size());
            double total = 0;
            for (std::uint32_t l = 0; l < lights.size(); ++l)
                total += pmf[l] = s.pmf(x, n, l, &memo);
            INFO("point " << p << " unbounded " << with_unbounded);
            if (!s.may_reach(x, n)) {
                CHECK(total == 0);
                continue;
            }
            ++reached;
            // A product of ≤ 64 branch probabilities per light, summed over
            // 3000 lights: 1 within a few thousand ulps.
            CHECK(total == Approx(1.0).epsilon(1e-12));
            if (p % 40 == 0) {
                // At significance kAlpha (a fixed-seed false alarm below
                // 1e-4), 200k draws fail a pmf that is off by a few per cent
                // on the lights drawn a few hundred times.
                CHECK(draws_pvalue(s, {x, n, 0.0}, pmf, 200000, rng) > testing::kAlpha);
                ++checked_draws;
            }
        }
        CHECK(reached > 150);
        CHECK(checked_draws >= 4);
    }
}

TEST_CASE("the light tree keeps every reaching light of a tiny cluster far from the origin",
          "[selection]") {
    // Triangles of 1–5 mm, 100 km from the origin, seen from 1–10 cm: single
    // precision there (x itself would round by up to 4 mm) must not cull a
    // light that reaches.
    const Vec3 far(1e5, -1e5, 1e5);
    Pcg32 rng(8, 3);
    std::vector<Light> lights;
    for (int i = 0; i < 400; ++i) {
        const Vec3 c = far + Vec3(rng.next_double(), rng.next_double(), rng.next_double()) * 0.05;
        const Frame f(random_direction(rng));
        const double size = 0.001 + 0.004 * rng.next_double();
        lights.push_back(make_triangle_light(c, c + f.to_world(Vec3(size, 0, 0)),
                                             c + f.to_world(Vec3(0, size, 0)), Vec3(1, 1, 1),
                                             false));
    }
    const LightSelector s(LightSelector::Kind::Tree, lights, all_ids(lights.size()), 10.0);
    int reaching = 0;
    for (int p = 0; p < 100; ++p) {
        const Vec3 x = far + Vec3(0.025, 0.025, 0.025) +
                       random_direction(rng) * (0.01 + 0.09 * rng.next_double());
        const Vec3 n = random_direction(rng);
        double total = 0;
        for (std::uint32_t l = 0; l < lights.size(); ++l) {
            const double pmf = s.pmf(x, n, l);
            total += pmf;
            if (unoccluded_irradiance(lights[l], x, n) > 0) {
                ++reaching;
                INFO("point " << p << " light " << l);
                CHECK(pmf > 0);
            }
        }
        if (s.may_reach(x, n)) CHECK(total == Approx(1.0).epsilon(1e-12));
    }
    CHECK(reaching > 1000);
}

TEST_CASE("a region's tree pmfs sum to 1, match draws, and keep every light that reaches "
          "any point inside", "[selection]") {
    // A texel's samples draw with its region's pmfs (direct_lighting.cpp):
    // unbiased only if every light that reaches some point of the region,
    // whatever its normal there, keeps a share.
    const std::vector<Light> lights = scattered_lights(3000, false);
    const LightSelector s(LightSelector::Kind::Tree, lights, all_ids(lights.size()), 10.0);
    Pcg32 rng(17, 2);
    int regions = 0, reaching = 0, checked_draws = 0;
    for (int r = 0; r < 60; ++r) {
        const Vec3 x(6 * rng.next_double() - 3, 6 * rng.next_double() - 3,
                     6 * rng.next_double() - 3);
        const LightSelector::Receiver region{x, random_direction(rng),
                                             std::pow(10.0, -2.5 + 2 * rng.next_double())};
        LightSelector::Memo memo;
        std::vector<double> pmf(lights.size());
        double total = 0;
        for (std::uint32_t l = 0; l < lights.size(); ++l)
            total += pmf[l] = s.pmf(region, l, &memo);
        INFO("region " << r << " radius " << region.radius);
        if (total == 0) continue;
        ++regions;
        CHECK(total == Approx(1.0).epsilon(1e-12));
        if (r % 20 == 0) {
            CHECK(draws_pvalue(s, region, pmf, 200000, rng) > testing::kAlpha);
            ++checked_draws;
        }
        // Points inside the ball (some on its sphere), with any normal.
        for (int p = 0; p < 20; ++p) {
            const double t = p < 5 ? 1.0 : std::cbrt(rng.next_double());
            const Vec3 y = x + random_direction(rng) * (t * region.radius);
            const Vec3 n = random_direction(rng);
            for (std::uint32_t l = 0; l < lights.size(); ++l) {
                if (!(unoccluded_irradiance(lights[l], y, n) > 0)) continue;
                ++reaching;
                INFO("point " << p << " light " << l);
                CHECK(pmf[l] > 0);
            }
        }
    }
    CHECK(regions > 40);
    CHECK(reaching > 10000);
    CHECK(checked_draws >= 2);
}

namespace {

// A ball of `count` small one-sided triangles about `centre`, of sizes over a
// decade, facing down (−z) within 20° — an emissive patch seen from afar —
// then, if `near` > 0, that many triangles scattered over [−1, 1]² at 0.2–0.5 m,
// facing down.
std::vector<Light> far_ball(int count, const Vec3& centre, double radius, int near) {
    Pcg32 rng(33, 7);
    std::vector<Light> lights;
    auto add = [&](const Vec3& c, double size) {
        const double tilt = 0.35 * rng.next_double(), phi = 2 * kPi * rng.next_double();
        const Vec3 normal(std::sin(tilt) * std::cos(phi), std::sin(tilt) * std::sin(phi),
                          -std::cos(tilt));
        const Frame f(normal);
        // make_triangle_light's normal is (p1 − p0) × (p2 − p0): f's x × y = normal.
        lights.push_back(make_triangle_light(c, c + f.to_world(Vec3(size, 0, 0)),
                                             c + f.to_world(Vec3(0, size, 0)), Vec3(1, 1, 1),
                                             false));
    };
    for (int i = 0; i < count; ++i) {
        const Vec3 c = centre + random_direction(rng) * (radius * std::cbrt(rng.next_double()));
        add(c, 0.003 * std::pow(10.0, rng.next_double()));
    }
    for (int i = 0; i < near; ++i)
        add(Vec3(2 * rng.next_double() - 1, 2 * rng.next_double() - 1,
                 0.2 + 0.3 * rng.next_double()),
            0.02 + 0.05 * rng.next_double());
    return lights;
}

}  // namespace

TEST_CASE("the light tree draws the lights of a small far cluster by power", "[selection]") {
    // 2000 triangles in a ball of 0.25 m, 5 m above the receivers: it
    // subtends less than asin(kClusterSine) = asin(0.1), and its normals lie
    // within 20° of −z, so each child of the root is a cluster
    // (light_selection.h): its lights share its probability ∝ their power.
    const std::vector<Light> lights = far_ball(2000, Vec3(0.3, -0.2, 5), 0.25, 0);
    const LightSelector s(LightSelector::Kind::Tree, lights, all_ids(lights.size()), 10.0);
    Pcg32 rng(12, 5);
    for (int p = 0; p < 4; ++p) {
        const Vec3 x(2 * rng.next_double() - 1, 2 * rng.next_double() - 1, 0);
        const Vec3 n(0, 0, 1);
        LightSelector::Memo memo;
        std::vector<double> pmf(lights.size()), per_power;
        double total = 0;
        for (std::uint32_t l = 0; l < lights.size(); ++l) {
            total += pmf[l] = s.pmf(x, n, l, &memo);
            REQUIRE(unoccluded_irradiance(lights[l], x, n) > 0);  // every light faces x
            REQUIRE(pmf[l] > 0);
            per_power.push_back(pmf[l] / LightSelector::bounds_of(lights[l], 10.0)->power);
        }
        CHECK(total == Approx(1.0).epsilon(1e-12));
        // pmf / power takes one value per cluster: at most the root's four
        // children (the walk through the tree would give each light its own,
        // by its distance and orientation).
        std::sort(per_power.begin(), per_power.end());
        int groups = 1;
        for (std::size_t i = 1; i < per_power.size(); ++i)
            if (per_power[i] > per_power[i - 1] * (1 + 1e-9)) ++groups;
        CHECK(groups <= 4);
        if (p == 0) CHECK(draws_pvalue(s, {x, n, 0.0}, pmf, 200000, rng) > testing::kAlpha);
        // Each light's draws are the u of one interval of length pmf (a
        // share of the root's children, then a step of its cluster's power
        // CDF): evenly spaced u then take it for pmf × count of them, give
        // or take one at each end (1e-16 of rounding moves an end). The
        // sizes vary 10×, so the search inside a cluster starts far from the
        // answer in both directions.
        const int grid = 1 << 20;
        std::vector<int> drawn(lights.size());
        for (int k = 0; k < grid; ++k) {
            const auto d = s.sample(x, n, (k + 0.5) / grid, &memo);
            REQUIRE(d);
            ++drawn[d->light];
        }
        double worst = 0;
        for (std::uint32_t l = 0; l < lights.size(); ++l)
            worst = std::max(worst, std::abs(drawn[l] - pmf[l] * grid));
        CHECK(worst < 2);
    }
}

TEST_CASE("light tree pmfs with far clusters and near lights sum to 1 and match draws",
          "[selection]") {
    // The far ball and 300 lights near the receivers: walks that end in a
    // cluster for some children and at single lights for others, at points
    // and over regions (a texel's ball, whose radius widens the clusters).
    const std::vector<Light> lights = far_ball(3000, Vec3(0, 0, 4), 0.3, 300);
    const LightSelector s(LightSelector::Kind::Tree, lights, all_ids(lights.size()), 10.0);
    Pcg32 rng(40, 1);
    int checked_draws = 0;
    for (int p = 0; p < 40; ++p) {
        const Vec3 x(3 * rng.next_double() - 1.5, 3 * rng.next_double() - 1.5,
                     0.1 * rng.next_double());
        const LightSelector::Receiver at{x, Vec3(0, 0, 1), p % 2 ? 0.02 : 0.0};
        LightSelector::Memo memo;
        std::vector<double> pmf(lights.size());
        double total = 0;
        for (std::uint32_t l = 0; l < lights.size(); ++l) {
            total += pmf[l] = s.pmf(at, l, &memo);
            // The tree never leaves out a light that reaches x.
            if (unoccluded_irradiance(lights[l], x, at.n) > 0) {
                INFO("point " << p << " light " << l);
                CHECK(pmf[l] > 0);
            }
        }
        INFO("point " << p);
        CHECK(total == Approx(1.0).epsilon(1e-12));
        if (p % 10 == 0) {
            // 200k draws at kAlpha, as above.
            CHECK(draws_pvalue(s, at, pmf, 200000, rng) > testing::kAlpha);
            ++checked_draws;
        }
    }
    CHECK(checked_draws == 4);
}

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST_CASE("a region's kept branching: later focuses draw and weigh as walks of the tree",
          "[selection]") {
    // A bake keeps each texel's branching between passes (Memo::keep_in) and
    // finds it when the memo next focuses on that texel, other texels
    // focused between. Its draws and pmfs must be those of a walk without a
    // memo, bit for bit: with a store that holds every node walked (16, 255)
    // or fills up (3), with clusters (the far ball) and unbounded lights,
    // and where kept nodes collide in the memo (every light's pmf with 255
    // kept: nodes that share one of its 2048 slots).
    const std::vector<Light> ball = far_ball(3000, Vec3(0, 0, 4), 0.3, 300),
                             scattered = scattered_lights(3000, true);
    for (const std::vector<Light>* lights : {&ball, &scattered})
        for (std::size_t capacity : {3, 16, 255}) {
            const LightSelector s(LightSelector::Kind::Tree, *lights, all_ids(lights->size()),
                                  10.0);
            Pcg32 rng(8, 3);
            std::vector<LightSelector::Receiver> regions;
            for (int r = 0; r < 12; ++r)
                regions.push_back({Vec3(3 * rng.next_double() - 1.5,
                                        3 * rng.next_double() - 1.5, 0.1 * rng.next_double()),
                                   Vec3(0, 0, 1), std::pow(10.0, -2.5 + 2 * rng.next_double())});
            std::vector<std::vector<LightSelector::KeptNode>> stores(
                regions.size(), std::vector<LightSelector::KeptNode>(capacity));
            LightSelector::Memo memo;
            int draws = 0;
            for (int pass = 0; pass < 3; ++pass)
                for (std::size_t r = 0; r < regions.size(); ++r) {
                    const LightSelector::Receiver& at = regions[r];
                    memo.keep_in(stores[r].data(), capacity);
                    INFO((lights == &ball ? "ball" : "scattered")
                         << ", " << capacity << " kept, pass " << pass << ", region " << r);
                    for (int d = 0; d < 16; ++d) {
                        const double u = rng.next_double();
                        const auto kept = s.sample(at, u, &memo), walked = s.sample(at, u);
                        REQUIRE(kept.has_value() == walked.has_value());
                        if (!kept) continue;
                        ++draws;
                        CHECK(kept->light == walked->light);
                        CHECK(same_bits(kept->pmf, walked->pmf));
                        CHECK(same_bits(kept->rest, walked->rest));
                        // Another light's pmf, as a BSDF sample asks for it.
                        const std::uint32_t other = rng.next_u32() % lights->size();
                        CHECK(same_bits(s.pmf(at, other, &memo), s.pmf(at, other)));
                    }
                    if (pass == 2 && capacity == 255)
                        for (std::uint32_t l = 0; l < lights->size(); ++l)
                            CHECK(same_bits(s.pmf(at, l, &memo), s.pmf(at, l)));
                }
            CHECK(draws > 300);
            // The stores hold the root first, then nodes below it, filled
            // from the front.
            for (const auto& store : stores) {
                std::size_t filled = 0;
                while (filled < capacity &&
                       store[filled].node_and_clusters != LightSelector::KeptNode::kNone)
                    ++filled;
                CHECK(filled > 0);
                CHECK((store[0].node_and_clusters &
                       ((1u << LightSelector::KeptNode::kClusterShift) - 1)) == 0);
                for (std::size_t j = filled; j < capacity; ++j)
                    CHECK(store[j].node_and_clusters == LightSelector::KeptNode::kNone);
                if (capacity == 3) CHECK(filled == 3);
            }
        }
}

TEST_CASE("a region's kept branching is what its draws use", "[selection]") {
    // The store is read, not only written: a root whose kept importance
    // gives every share to its first child draws nothing from the others,
    // and another store for the same receiver is filled anew (keep_in
    // refocuses the memo on an equal receiver).
    const std::vector<Light> lights = scattered_lights(3000, false);
    const LightSelector s(LightSelector::Kind::Tree, lights, all_ids(lights.size()), 10.0);
    const LightSelector::Receiver at{Vec3(0.3, -0.2, 0.05), Vec3(0, 0, 1), 0.01};
    std::vector<LightSelector::KeptNode> store(8), other(8);
    LightSelector::Memo memo;
    memo.keep_in(store.data(), store.size());
    std::vector<double> pmf(lights.size());
    for (std::uint32_t l = 0; l < lights.size(); ++l) pmf[l] = s.pmf(at, l, &memo);
    REQUIRE(store[0].node_and_clusters == 0);  // the root, no child a cluster
    int shares = 0;
    for (float importance : store[0].importance) shares += importance > 0;
    REQUIRE(shares >= 2);  // so that the first child alone is a change
    memo.keep_in(other.data(), other.size());
    CHECK(same_bits(s.pmf(at, 0, &memo), pmf[0]));
    CHECK(other[0].node_and_clusters == 0);  // the same receiver, kept anew
    // Only the first child's lights: all of its importance, none elsewhere.
    store[0].importance[1] = store[0].importance[2] = store[0].importance[3] = 0;
    memo.keep_in(store.data(), store.size());
    int dropped = 0;
    double total = 0;
    for (std::uint32_t l = 0; l < lights.size(); ++l) {
        const double p = s.pmf(at, l, &memo);
        dropped += pmf[l] > 0 && p == 0;
        total += p;
    }
    CHECK(dropped > 0);
    CHECK(total == Approx(1.0).epsilon(1e-12));
}

TEST_CASE("a draw begun ahead and finished later is sample()'s, and pmfs through its memo stay "
          "right",
          "[selection]") {
    // shade draws each sample's light in two halves: begun two samples
    // ahead, finished one ahead (begin_draw, finish_draw), the memo asked
    // for other draws and pmfs in between — at the same receiver, and now
    // and then at another (a sample outside a texel's region). Each draw
    // must be sample()'s bit for bit, and a pmf through that memo a walk's:
    // a draw ahead must not leave the memo's shortcut for "the light just
    // drawn" (Memo::drawn) holding a light of another draw or receiver.
    std::vector<Light> lights = far_ball(3000, Vec3(0, 0, 4), 0.3, 300);
    lights.push_back(make_sun_light(Vec3(0, 0.3, -1), Vec3(1, 1, 1), 0.1));
    lights.push_back(make_world_light(Vec3(1, 1, 1) * 0.1));
    const std::vector<std::uint32_t> ids = all_ids(lights.size());
    const LightSelector::Kind kinds[] = {LightSelector::Kind::Uniform,
                                         LightSelector::Kind::Power, LightSelector::Kind::Tree};
    for (auto kind : kinds) {
        const LightSelector s(kind, lights, ids, 10.0);
        Pcg32 rng(17, 2);
        int in_cluster = 0, at_leaf = 0, unbounded = 0;
        for (int p = 0; p < 24; ++p) {
            const Vec3 x(3 * rng.next_double() - 1.5, 3 * rng.next_double() - 1.5,
                         0.1 * rng.next_double());
            const LightSelector::Receiver at{x, Vec3(0, 0, 1), p % 2 ? 0.02 : 0.0},
                elsewhere{x + Vec3(0.4, -0.3, 0), normalize(Vec3(0.2, 0, 1)), 0.0};
            constexpr int kDraws = 400;
            std::vector<LightSelector::Receiver> where;
            std::vector<double> u;
            for (int k = 0; k < kDraws; ++k) {
                where.push_back(k % 7 == 3 ? elsewhere : at);
                u.push_back(rng.next_double());
            }
            LightSelector::Memo memo;
            std::vector<LightSelector::PartialDraw> begun(kDraws);
            begun[0] = s.begin_draw(where[0], u[0], &memo);
            begun[1] = s.begin_draw(where[1], u[1], &memo);
            for (int k = 0; k < kDraws; ++k) {
                INFO("kind " << int(kind) << " point " << p << " draw " << k);
                const auto light = s.finish_draw(begun[k]);
                if (k + 2 < kDraws) begun[k + 2] = s.begin_draw(where[k + 2], u[k + 2], &memo);
                const auto drawn = s.sample(where[k], u[k]);
                REQUIRE(light.has_value() == drawn.has_value());
                if (!light) continue;
                in_cluster += begun[k].in_cluster;
                at_leaf += begun[k].from_tree && !begun[k].in_cluster;
                unbounded += light->light >= 3300;  // the sun, the world
                CHECK(light->light == drawn->light);
                CHECK(same_bits(light->pmf, drawn->pmf));
                CHECK(same_bits(light->rest, drawn->rest));
                // The light's pmf, and another's, through the memo; now and
                // then after a whole sample() there, which tells the memo
                // its light.
                if (k % 5 == 0) s.sample(where[k], rng.next_double(), &memo);
                CHECK(same_bits(s.pmf(where[k], light->light, &memo),
                                s.pmf(where[k], light->light)));
                const std::uint32_t other = rng.next_u32() % lights.size();
                CHECK(same_bits(s.pmf(where[k], other, &memo), s.pmf(where[k], other)));
            }
        }
        // The tree's draws took each way: beside the tree (2 of its 3
        // choices), into a cluster, and down to a single light.
        if (kind == LightSelector::Kind::Tree) {
            CHECK(unbounded > 1000);
            CHECK(in_cluster > 400);
            CHECK(at_leaf > 1000);
        }
    }
}
