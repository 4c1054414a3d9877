// An image-based world's build cost: an 8192 × 4096 procedural sky (a
// gradient and a 0.5° sun disc 1e5 times as bright) made into an
// EnvironmentMap, plain and with MIS compensation — the wall time of the
// build, the bytes it holds, and the cost of a draw and of a density.
// Usage: omis_bench_environment_map [width height]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "lights/environment_map.h"

using namespace omis;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Rows top first (Cycles' convention, environment_map.h): a blue-to-white
// sky above the horizon, a dim ground, a sun of angular diameter 0.5° at
// 40° elevation along +X·cos + Y·sin(30°).
std::vector<float> procedural_sky(int w, int h) {
    std::vector<float> rgb(std::size_t(w) * h * 3);
    const double elevation = 40 * kPi / 180, azimuth = 30 * kPi / 180;
    const Vec3 sun{std::cos(elevation) * std::cos(azimuth),
                   std::cos(elevation) * std::sin(azimuth), std::sin(elevation)};
    const double cos_sun = std::cos(0.25 * kPi / 180);
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
            const Vec3 d = EnvironmentMap::equirectangular_to_direction(
                {(c + 0.5) / w, 1 - (r + 0.5) / h});
            Vec3 l = d.z > 0 ? Vec3(0.3, 0.5, 1.0) * (1 - d.z) + Vec3(0.1, 0.2, 0.6) * d.z
                             : Vec3(0.05, 0.04, 0.03);
            if (dot(d, sun) >= cos_sun) l = Vec3(1e5, 0.95e5, 0.9e5);
            float* p = &rgb[(std::size_t(r) * w + c) * 3];
            p[0] = float(l.x), p[1] = float(l.y), p[2] = float(l.z);
        }
    return rgb;
}

void measure(const std::vector<float>& rgb, int w, int h, bool compensate) {
    auto t0 = Clock::now();
    const EnvironmentMap map(rgb, w, h, Vec3(0, 0, 0.3), compensate);
    const double build = seconds_since(t0);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    const int draws = 1000000;
    double checksum = 0;
    t0 = Clock::now();
    for (int i = 0; i < draws; ++i) {
        const auto s = map.sample(uni(rng), uni(rng));
        if (s) checksum += s->pdf;
    }
    const double sample_ns = seconds_since(t0) / draws * 1e9;
    std::normal_distribution<double> g;
    t0 = Clock::now();
    for (int i = 0; i < draws; ++i)
        checksum += map.pdf(normalize(Vec3(g(rng), g(rng), g(rng))));
    const double pdf_ns = seconds_since(t0) / draws * 1e9;
    const double image_mib = double(rgb.size() * sizeof(float)) / (1 << 20);
    std::printf(
        "%-12s build %.3f s  holds %.0f MiB (image %.0f MiB, distribution %.0f MiB)"
        "  draw %.0f ns  pdf %.0f ns  (checksum %.3g)\n",
        compensate ? "compensated" : "plain", build,
        double(map.memory_bytes()) / (1 << 20), image_mib,
        double(map.memory_bytes()) / (1 << 20) - image_mib, sample_ns, pdf_ns, checksum);
}

}  // namespace

int main(int argc, char** argv) {
    const int w = argc > 2 ? std::atoi(argv[1]) : 8192,
              h = argc > 2 ? std::atoi(argv[2]) : 4096;
    const auto t0 = Clock::now();
    const std::vector<float> rgb = procedural_sky(w, h);
    std::printf("world image %d x %d (procedural sky, made in %.2f s)\n", w, h,
                seconds_since(t0));
    measure(rgb, w, h, false);
    measure(rgb, w, h, true);
    return 0;
}
