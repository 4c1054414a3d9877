// Light-shape samplers, one run, ratios only (timings on a shared machine vary).
//
// Part A: the per-draw estimator L·cos θ/pdf of E at one point, old sampler vs new:
//   relative variance per draw, time per draw, and efficiency = 1/(variance·time) as
//   a ratio new/old (> 1: the new sampler wins at equal time).
// Part B: direct lighting of a floor under a rect light with an occluder, each light
//   technique alone: relative MSE against a long projected-solid-angle reference,
//   time, and efficiency relative to uniform/solid-angle.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "lights/light.h"
#include "render/direct_lighting.h"

using namespace omis;
using Clock = std::chrono::steady_clock;

namespace {

using Sampler = std::function<std::optional<LightSample>(double, double)>;

struct Stats {
    double rel_var = 0, ns = 0;
};

Stats per_draw(const Light& l, const Vec3& x, const Vec3& n, const Sampler& sample, int count) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    double sum = 0, sum2 = 0;
    const auto t0 = Clock::now();
    for (int i = 0; i < count; ++i) {
        const auto s = sample(uni(rng), uni(rng));
        double v = 0;
        if (s) {
            const auto e = emitted_radiance(l, x, s->dir);
            if (e) v = luminance(e->radiance) * std::max(0.0, dot(n, s->dir)) / s->pdf;
        }
        sum += v;
        sum2 += v * v;
    }
    const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
    const double mean = sum / count;
    return {std::max(0.0, sum2 / count - mean * mean) / (mean * mean), 1e9 * secs / count};
}

void compare(const char* name, const Light& l, const Vec3& x, const Vec3& n,
             const std::vector<std::pair<const char*, Sampler>>& samplers) {
    const int count = 200000;
    const Stats base = per_draw(l, x, n, samplers[0].second, count);
    for (const auto& [label, s] : samplers) {
        const Stats st = per_draw(l, x, n, s, count);
        const double eff = (base.rel_var * base.ns) / std::max(st.rel_var * st.ns, 1e-300);
        std::printf("  %-34s %-26s rel.var/draw %10.3g  ns/draw %7.1f  efficiency ×%s\n",
                    name, label, st.rel_var, st.ns,
                    st.rel_var < 1e-20 ? "∞ (zero variance)" : std::to_string(eff).c_str());
    }
}

Sampler through(const Light& l, ShapeSampler s, const Vec3& x, const Vec3& n) {
    return [&l, s, x, n](double u1, double u2) { return sample_light(l, s, x, n, u1, u2); };
}

void part_a() {
    std::printf("Part A: per-draw estimator at one point (first row of each case = baseline)\n");
    const Vec3 up{0, 0, 1}, white{1, 1, 1};
    const double deg = kPi / 180;
    {
        const Light l = make_rect_light({-1, -1, 0.3}, {0, 2, 0}, {2, 0, 0}, white, false, 30 * deg);
        const Vec3 x{0.2, 0.1, 0};
        compare("rect 2 m, spread 30°, 0.3 m", l, x, up,
                {{"whole rect (old)", [&](double a, double b) { return l.rect.sample_solid_angle(x, a, b); }},
                 {"spread-clamped (new)", through(l, ShapeSampler::SolidAngle, x, up)}});
    }
    {
        const Light l = make_rect_light({1, -1, -0.5}, {0, 0, 2}, {0, 2, 0}, white, false, 10 * deg);
        const Vec3 x{0.2, 0.3, 0.4}, n = normalize(Vec3{1, 0, 0.2});
        compare("wall rect, spread 10°, 0.8 m", l, x, n,
                {{"whole rect (old)", [&](double a, double b) { return l.rect.sample_solid_angle(x, a, b); }},
                 {"spread-clamped (new)", through(l, ShapeSampler::SolidAngle, x, n)}});
    }
    {
        const Light l = make_ellipse_light({0, 0, 0.3}, {0, 1, 0}, {1, 0, 0}, white, false, 30 * deg);
        const Vec3 x{0.2, 0.1, 0};
        compare("disk r 1 m, spread 30°, 0.3 m", l, x, up,
                {{"whole disk, area (old)", [&](double a, double b) { return l.ellipse.sample_area(x, a, b); }},
                 {"spread-clipped (new)", through(l, ShapeSampler::SolidAngle, x, up)}});
    }
    for (auto [name, r, h, px] : {std::tuple{"disk r 0.5 m, 5 cm above", 0.5, 0.05, 0.1},
                                  std::tuple{"disk r 1 m, 1 cm above", 1.0, 0.01, 0.3},
                                  std::tuple{"disk r 30 m, 1 m above", 30.0, 1.0, 2.0}}) {
        const Light l = make_ellipse_light({0, 0, h}, {0, r, 0}, {r, 0, 0}, white, false, kPi);
        const Vec3 x{px, 0, 0};
        compare(name, l, x, up,
                {{"area (old solid-angle)", through(l, ShapeSampler::Area, x, up)},
                 {"spherical ellipse (new)", through(l, ShapeSampler::SolidAngle, x, up)}});
    }
    struct Poly {
        const char* name;
        Light light;
        Vec3 x, n;
    };
    const Poly polys[] = {
        {"rect 1 m at 1 m", make_rect_light({-0.5, -0.5, 1}, {0, 1, 0}, {1, 0, 0}, white, false, kPi), {0.3, 0, 0}, up},
        {"rect 1 m at 5 cm", make_rect_light({-0.5, -0.5, 0.05}, {0, 1, 0}, {1, 0, 0}, white, false, kPi), {0.3, 0, 0}, up},
        {"wall rect across the horizon", make_rect_light({2, -0.5, -0.5}, {0, 0, 1}, {0, 1, 0}, white, false, kPi), {0, 0, 0}, up},
        {"rect 20 m at 1 m", make_rect_light({-10, -10, 1}, {0, 20, 0}, {20, 0, 0}, white, false, kPi), {2, 1, 0}, up},
        {"triangle, tilted receiver", make_triangle_light({-1, 0, 0.5}, {1, -0.5, 0.7}, {0.2, 1, 0.4}, white, true), {0, 0, 0}, normalize(Vec3{0.3, 0.2, 1})},
    };
    for (const Poly& p : polys) {
        std::vector<std::pair<const char*, Sampler>> s = {
            {"solid-angle", through(p.light, ShapeSampler::SolidAngle, p.x, p.n)},
            {"projected-solid-angle", through(p.light, ShapeSampler::ProjectedSolidAngle, p.x, p.n)}};
        if (sampler_applies(p.light, ShapeSampler::Parallel, p.x, p.n))
            s.push_back({"parallel", through(p.light, ShapeSampler::Parallel, p.x, p.n)});
        compare(p.name, p.light, p.x, p.n, s);
    }
}

// A 4 m floor of points under a 1 m ceiling rect at 1 m, a 0.4 m box floating at 0.5 m.
void part_b() {
    std::printf("\nPart B: floor under a rect light with an occluder, 48×48 points, 4 samples × 4 rounds\n");
    Scene scene;
    scene.add_light(make_rect_light({-0.5, -0.5, 1}, {0, 1, 0}, {1, 0, 0}, {3, 3, 3}, false, kPi));
    const double b0 = -0.2, b1 = 0.2, z0 = 0.4, z1 = 0.6;
    std::vector<Vec3> pos;
    for (int i = 0; i < 8; ++i)
        pos.push_back({i & 1 ? b1 : b0, i & 2 ? b1 : b0, i & 4 ? z1 : z0});
    const std::vector<std::array<std::uint32_t, 3>> tris = {
        {0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
        {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
    scene.add_mesh(pos, tris);
    scene.commit();
    const int g = 48;
    std::vector<double> points, normals;
    for (int i = 0; i < g; ++i)
        for (int j = 0; j < g; ++j) {
            points.insert(points.end(), {-2 + 4 * (i + 0.5) / g, -2 + 4 * (j + 0.5) / g, 0});
            normals.insert(normals.end(), {0, 0, 1});
        }
    const std::size_t count = g * g;
    auto run = [&](std::vector<std::string> names, std::vector<int> samples, int rounds,
                   std::vector<double>& out) {
        DirectLightingSettings s;
        for (auto& nm : names) s.techniques.push_back(*parse_technique(nm));
        s.samples = samples;
        s.rounds = rounds;
        s.seed = 11;
        out.assign(3 * count, 0);
        std::vector<double> var(3 * count);
        return direct_lighting(scene, points.data(), normals.data(), count, s, out.data(), var.data())
            .seconds;
    };
    std::vector<double> ref;
    run({"uniform/projected-solid-angle", "uniform/solid-angle"}, {16, 16}, 64, ref);
    struct Row {
        std::string label;
        std::vector<std::string> names;
        std::vector<int> samples;
    };
    const std::vector<Row> rows = {
        {"uniform/solid-angle", {"uniform/solid-angle"}, {4}},
        {"uniform/parallel", {"uniform/parallel"}, {4}},
        {"uniform/projected-solid-angle", {"uniform/projected-solid-angle"}, {4}},
        {"default: solid-angle + area", {"uniform/solid-angle", "uniform/area"}, {2, 2}},
        {"projected-solid-angle + area", {"uniform/projected-solid-angle", "uniform/area"}, {2, 2}},
    };
    double base_eff = 0;
    for (const Row& r : rows) {
        std::vector<double> out;
        const double secs = run(r.names, r.samples, 4, out);
        double mse = 0;
        int lit = 0;
        for (std::size_t i = 0; i < count; ++i) {
            const double e = ref[3 * i + 1];
            if (e <= 0) continue;
            mse += (out[3 * i + 1] - e) * (out[3 * i + 1] - e) / (e * e);
            ++lit;
        }
        mse /= std::max(lit, 1);
        const double eff = 1 / (mse * secs);
        if (base_eff == 0) base_eff = eff;
        std::printf("  %-32s relMSE %10.3g  time %6.3f s  efficiency ×%.2f\n", r.label.c_str(),
                    mse, secs, eff / base_eff);
    }
}

}  // namespace

int main() {
    part_a();
    part_b();
}
