// closest_hit_and_emitters' near-edge rule (kNearEdge): where single
// precision lets a ray miss an emissive triangle it crosses exactly (in
// double, as the callers' emitted_radiance tests it), a neighbour's hit near
// the shared edge leaves the list incomplete. Rays aimed within a few ulps of
// the shared edges and vertices of a fine emissive grid: every light the ray
// crosses exactly is listed, or the list is marked incomplete.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "render/scene.h"

using namespace omis;

TEST_CASE("closest_hit_and_emitters: a ray single precision moves off a light it crosses "
          "leaves the list incomplete",
          "[scene][emitters]") {
    // 24 × 24 quads of 1 cm, tilted (no coordinate constant over the grid),
    // at the scale kNearEdge is sized for: coordinates ~1, origins 2 away.
    // (Far from the world origin or with cells under ~1 mm at metres, the
    // float rounding of the ray and the vertices exceeds kNearEdge: see
    // bench/results/emitters.txt, emitter-query edges.)
    constexpr int n = 24;
    const Vec3 centre(0.3, -0.2, 1.1);
    const Vec3 a = normalize(Vec3(1, 0.3, 0.2)) * 0.01;
    const Vec3 b = normalize(cross(Vec3(0.2, -0.4, 1), a)) * 0.01;
    const Vec3 normal = normalize(cross(a, b));
    std::vector<Vec3> p;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) p.push_back(centre + a * (i - n / 2.0) + b * (j - n / 2.0));
    std::vector<std::array<std::uint32_t, 3>> t;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const std::uint32_t v = i * (n + 1) + j;
            t.push_back({v, v + n + 1, v + n + 2});
            t.push_back({v, v + n + 2, v + 1});
        }
    Scene scene;
    scene.add_mesh(p, t, Vec3(1, 1, 1));
    scene.commit();
    const GeometryScene& geometry = scene.geometry();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    std::uniform_int_distribution<int> quad(2, n - 3);
    int moved_off = 0, unlisted_on_complete = 0;
    for (int k = 0; k < 6000; ++k) {
        // A point on a quad's diagonal or side, or a vertex (k % 3), moved by
        // up to 4 ulps of its coordinates; the ray from 2 away, obliquely.
        const int i = quad(rng), j = quad(rng);
        const double s = 0.5 + 0.5 * u(rng);
        Vec3 target = centre + a * (i - n / 2.0) + b * (j - n / 2.0);
        if (k % 3 == 0) target = target + (a + b) * s;
        if (k % 3 == 1) target = target + a * s;
        const double ulp = std::ldexp(1.0, std::ilogb(length(target)) - 23);
        target = target + Vec3(u(rng), u(rng), u(rng)) * (4 * ulp);
        const Vec3 o = target + (normal + normalize(Vec3(u(rng), u(rng), u(rng))) * 0.8) * 2.0;
        const Vec3 d = target - o;
        std::vector<std::uint32_t> lights;
        bool complete = false;
        const auto hit = geometry.closest_hit_and_emitters(o, d, lights, complete);
        // A ray through a vertex that float lets miss every triangle there
        // (3 in 20,000 of these rays; no hit to judge by) is beyond the rule.
        if (!hit) continue;
        std::sort(lights.begin(), lights.end());
        INFO("ray " << k);
        for (std::uint32_t l = 0; l < scene.lights().size(); ++l) {
            if (!emitted_radiance(scene.lights()[l], o, normalize(d))) continue;
            if (std::binary_search(lights.begin(), lights.end(), l)) continue;
            ++moved_off;
            if (complete) ++unlisted_on_complete;
        }
    }
    CHECK(unlisted_on_complete == 0);
    // The case happens: the test can fail where the margin is too narrow.
    CHECK(moved_off > 100);
}
