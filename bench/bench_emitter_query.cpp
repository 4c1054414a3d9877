// What the emitter query costs as the emitters grow, against the queries an
// estimator that needs fewer lights would trace (issue 8's growth target).
//
// A light technique's density sums over every light that covers a direction,
// hidden ones too (SPEC §3): a ray into a closed emissive mesh must list its
// far side as well as the near side it hits, so omis's emitter query
// (GeometryScene::closest_hit_and_emitters) carries the ray through the whole
// mesh. This prints, per emissive UV sphere of 16 to ~100k triangles over a
// floor (bench_emitters.cpp's scenes), the time of one such query beside one
// closest hit (the near side alone) and two closest hits (the near side, and
// the far side from beyond the sphere back toward the floor), on the same
// rays: floor points toward uniform points on the sphere, as area sampling of
// its triangles draws them. One thread; the three alternate over --reps
// repeats and the median is printed.
//
//   build/bench/omis_bench_emitter_query [--rays N] [--reps N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "render/scene.h"
#include "support/emissive_sphere.h"

using namespace omis;

namespace {

const Vec3 kCentre(0, 0, 1.5);
constexpr double kRadius = 0.5;

struct QueryRay {
    Vec3 origin, direction;
};

// Floor points in [−2, 2]² toward uniform points on the sphere; fixed seed.
std::vector<QueryRay> sphere_rays(int count) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<QueryRay> rays(static_cast<std::size_t>(count));
    for (QueryRay& r : rays) {
        r.origin = Vec3(-2 + 4 * u(rng), -2 + 4 * u(rng), 1e-4);
        const double z = 1 - 2 * u(rng), phi = 2 * kPi * u(rng), s = std::sqrt(1 - z * z);
        const Vec3 target = kCentre + kRadius * Vec3(s * std::cos(phi), s * std::sin(phi), z);
        r.direction = normalize(target - r.origin);
    }
    return rays;
}

double seconds_of(const std::function<void()>& run) {
    const auto start = std::chrono::steady_clock::now();
    run();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Where the timed loops' results go, so that the compiler keeps the queries.
volatile std::size_t result_sink = 0;

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    int ray_count = 100000, reps = 5;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--rays") && i + 1 < argc) ray_count = std::atoi(argv[++i]);
        else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
        else {
            std::fprintf(stderr, "usage: %s [--rays N] [--reps N]\n", argv[0]);
            return 2;
        }
    }
    if (ray_count < 1 || reps < 1) {
        std::fprintf(stderr, "%s: --rays and --reps must be positive\n", argv[0]);
        return 2;
    }
    const std::vector<QueryRay> rays = sphere_rays(ray_count);
    std::printf("ns per query, one thread, %d rays from a floor toward uniform points on an "
                "emissive UV sphere (median of %d)\n", ray_count, reps);
    std::printf("%9s %12s %8s %12s %8s %14s %8s %14s\n", "emitters", "all lights", "growth",
                "closest hit", "growth", "two closest", "growth", "lights listed");
    double first[3] = {0, 0, 0};
    const std::pair<int, int> spheres[] = {{2, 8}, {8, 16}, {20, 40}, {64, 128}, {158, 316}};
    for (auto [stacks, slices] : spheres) {
        Scene scene;
        scene.add_mesh(std::vector<Vec3>{{-5, -5, 0}, {5, -5, 0}, {5, 5, 0}, {-5, 5, 0}},
                       {{0, 1, 2}, {0, 2, 3}});
        testing::add_emissive_sphere(scene, kCentre, kRadius, stacks, slices);
        scene.set_mesh_lights(false);  // its triangles as lights: the query lists them
        scene.commit();
        const GeometryScene& geometry = scene.geometry();
        const double inf = std::numeric_limits<double>::infinity();
        std::vector<std::uint32_t> lights;
        std::size_t listed = 0, checksum = 0;
        // The emitter query as integrand_to_blocker traces it.
        auto all_lights = [&] {
            listed = 0;
            for (const QueryRay& r : rays) {
                lights.clear();
                bool complete = false;
                const auto hit =
                    geometry.closest_hit_and_emitters(r.origin, r.direction, lights, complete);
                listed += lights.size();
                checksum += hit ? hit->triangle : 0;
            }
        };
        auto closest = [&] {
            for (const QueryRay& r : rays) {
                const auto hit = geometry.closest_hit(r.origin, r.direction, 0, inf);
                checksum += hit ? hit->triangle : 0;
            }
        };
        // The far side from a point beyond the sphere, back toward the floor,
        // as far as the near side's hit.
        auto two_closest = [&] {
            for (const QueryRay& r : rays) {
                const auto hit = geometry.closest_hit(r.origin, r.direction, 0, inf);
                if (!hit) continue;
                const double beyond = length(kCentre - r.origin) + 2 * kRadius;
                const auto far = geometry.closest_hit(r.origin + beyond * r.direction,
                                                      -r.direction, 0, beyond - hit->t);
                checksum += hit->triangle + (far ? far->triangle : 0);
            }
        };
        std::vector<double> times[3];
        for (int rep = 0; rep < reps; ++rep) {
            times[0].push_back(seconds_of(all_lights));
            times[1].push_back(seconds_of(closest));
            times[2].push_back(seconds_of(two_closest));
        }
        double ns[3];
        for (int m = 0; m < 3; ++m) {
            ns[m] = 1e9 * median(times[m]) / ray_count;
            if (first[m] == 0) first[m] = ns[m];
        }
        const int emitters = 2 * slices * (stacks - 1);
        std::printf("%9d %12.1f %7.2fx %12.1f %7.2fx %14.1f %7.2fx %14.2f\n", emitters, ns[0],
                    ns[0] / first[0], ns[1], ns[1] / first[1], ns[2], ns[2] / first[2],
                    double(listed) / ray_count);
        result_sink = checksum;  // the queries' results are used
    }
    return 0;
}
