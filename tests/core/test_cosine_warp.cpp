// The `solid-angle` sampler of rects and triangles at a receiver (CosineWarped:
// the spherical shape's square bent by a piecewise-bilinear density through cos θ), with
// the sampler checker: draws finite, pdf() equal to the draw's pdf, mean of
// 1/pdf equal to the solid angle, and chi-square of cells of the shape's own
// parametrisation against the piecewise-bilinear density's exact cell
// integrals. And the warp alone against its closed form.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "sampler_check.h"
#include "sampling/cosine_warp.h"
#include "sampling/shapes.h"

using namespace omis;
using namespace omis::testing;

namespace {

constexpr int K = 6;  // cells per side of the parameter square

// The piecewise-bilinear density through node weights w (g × g patches),
// written out independently of the code under test.
double density(double x, double y, const std::vector<double>& w, int g) {
    const int n = g + 1;
    const int i = std::min(g - 1, int(x * g)), j = std::min(g - 1, int(y * g));
    const double s = x * g - i, t = y * g - j;
    const double f = (1 - s) * (1 - t) * w[j * n + i] + s * (1 - t) * w[j * n + i + 1] +
                     (1 - s) * t * w[(j + 1) * n + i] + s * t * w[(j + 1) * n + i + 1];
    double total = 0;  // ∫ = mean of the patches' corner means
    for (int b = 0; b < g; ++b)
        for (int a = 0; a < g; ++a)
            total += 0.25 * (w[b * n + a] + w[b * n + a + 1] + w[(b + 1) * n + a] +
                             w[(b + 1) * n + a + 1]);
    return f / (total / (g * g));
}

// Exact probability of cell (i, j) of the K × K grid: each cell lies inside one
// patch (K is a multiple of g), where the density is bilinear, so the midpoint
// rule is exact.
double cell_probability(int i, int j, const std::vector<double>& w, int g) {
    return density((i + 0.5) / K, (j + 0.5) / K, w, g) / (K * K);
}

int grid_cell(const Point2& p) {
    const int i = std::min(K - 1, std::max(0, int(p.x * K)));
    const int j = std::min(K - 1, std::max(0, int(p.y * K)));
    return i * K + j;
}

// The warp's node weights as its documentation states them: cos θ at the
// directions a (g + 1) × (g + 1) grid of the square maps to, floored.
template <class Shape>
std::vector<double> node_weights(const Shape& s, const Vec3& n, int g) {
    std::vector<double> w;
    for (int j = 0; j <= g; ++j)
        for (int i = 0; i <= g; ++i)
            w.push_back(std::max(CosineWarped<Shape>::kMinCosine,
                                 dot(n, s.sample(double(i) / g, double(j) / g).dir)));
    return w;
}

struct Receiver {
    std::string name;
    Vec3 x, n;
};

const Receiver kReceivers[] = {
    {"below the centre", {0, 0, 0}, {0, 0, 1}},
    {"offset, 0.4 m below", {0.9, -0.3, 0.6}, {0, 0, 1}},
    {"tilted receiver", {0.2, 0.1, 0.2}, normalize(Vec3{0.6, -0.3, 1})},
    {"light straddling the horizon", {0, 0, 1}, {1, 0, 0}},
};

template <class Light, class Shape>
void check_warped(const std::string& name, const Light& L, const Shape& shape,
                  const Receiver& r, std::uint64_t seed) {
    constexpr int g = CosineWarped<Shape>::kPatches;
    static_assert(K % g == 0, "cells must lie inside one patch");
    const std::vector<double> w = node_weights(shape, r.n, g);
    SamplerUnderTest t;
    t.name = name + ", " + r.name;
    t.sample = [&](double u1, double u2) { return L.sample_solid_angle(r.x, r.n, u1, u2); };
    t.pdf = [&](const Vec3& d) { return L.pdf_solid_angle(r.x, r.n, d); };
    t.bin = [&](const Vec3& d) { return shape.pdf(d) > 0 ? grid_cell(shape.invert(d)) : -1; };
    for (int i = 0; i < K; ++i)
        for (int j = 0; j < K; ++j) t.cell_prob.push_back(cell_probability(i, j, w, g));
    t.measure = shape.solid_angle();
    run_sampler_check(t, seed);
}

}  // namespace

TEST_CASE("piecewise-bilinear warp: cells hold their exact share", "[sampling][warp]") {
    struct Case {
        int g;
        std::vector<double> w;
    };
    const Case cases[] = {{1, {1, 1, 1, 1}},
                          {1, {0.01, 1, 0.5, 0.2}},
                          {1, {3, 0.01, 0.01, 0.01}},
                          {2, {0.1, 0.3, 0.1, 0.3, 1.0, 0.4, 0.1, 0.5, 0.2}},
                          {2, {0.01, 0.01, 0.01, 0.01, 2.0, 0.01, 0.01, 0.01, 0.01}}};
    std::uint64_t seed = 9100;
    for (const Case& c : cases) {
        SamplerUnderTest t;
        t.name = "piecewise bilinear, g = " + std::to_string(c.g) + ", seed " + std::to_string(seed);
        // Square points as directions (x, y, 1): the checker bins directions.
        t.sample = [&](double u1, double u2) -> std::optional<LightSample> {
            const Point2 p = sample_piecewise_bilinear(u1, u2, c.w.data(), c.g);
            return LightSample{normalize(Vec3(p.x, p.y, 1.0)), 1.0,
                               pdf_piecewise_bilinear(p, c.w.data(), c.g)};
        };
        t.pdf = [&](const Vec3& d) {
            return pdf_piecewise_bilinear({d.x / d.z, d.y / d.z}, c.w.data(), c.g);
        };
        t.bin = [&](const Vec3& d) { return grid_cell({d.x / d.z, d.y / d.z}); };
        for (int i = 0; i < K; ++i)
            for (int j = 0; j < K; ++j) t.cell_prob.push_back(cell_probability(i, j, c.w, c.g));
        t.measure = 1.0;  // the square's area: E[1/pdf] = 1
        run_sampler_check(t, seed++);
        // And the density against the independent formula.
        for (double x : {0.1, 0.5, 0.77})
            for (double y : {0.05, 0.5, 0.93})
                CHECK(pdf_piecewise_bilinear({x, y}, c.w.data(), c.g) ==
                      Approx(density(x, y, c.w, c.g)).epsilon(1e-12));
    }
}

TEST_CASE("solid-angle sampler bent toward cos θ: rect and triangle", "[sampling][warp]") {
    const RectLight rect{{-0.5, -0.4, 0.8}, {1.0, 0, 0}, {0, 0.8, 0}};
    const TriangleLight tri{{-0.5, -0.4, 0.8}, {0.6, -0.3, 0.9}, {0.1, 0.6, 0.7}};
    std::uint64_t seed = 9200;
    for (const Receiver& r : kReceivers) {
        const auto sr = SphericalRect::make(r.x, rect.corner, rect.edge_u, rect.edge_v);
        const auto st = SphericalTriangle::make(r.x, tri.p0, tri.p1, tri.p2);
        REQUIRE(sr);
        REQUIRE(st);
        check_warped("rect", rect, *sr, r, seed++);
        check_warped("triangle", tri, *st, r, seed++);
    }
}

TEST_CASE("bent toward cos θ, an unoccluded Lambert estimate varies less", "[sampling][warp]") {
    // The point of the warp: cos θ/pdf is nearer constant than with uniform
    // solid angle (1/Ω). Same 32 × 32 stratified uniforms for both. A wide
    // light off to the side, low over the receiver: cos θ runs from 0.45 to
    // 0.05 across it (the case the corner weights follow; not a light
    // straight above x, whose cos θ peaks inside).
    const RectLight rect{{0.5, -1, 0.5}, {2, 0, 0}, {0, 2, 0}};
    const Vec3 x(0, 0, 0), n(0, 0, 1);
    double sum[2] = {}, sum2[2] = {};
    const int m = 32;
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
            const double u1 = (i + 0.5) / m, u2 = (j + 0.5) / m;
            const auto a = rect.sample_solid_angle(x, u1, u2);
            const auto b = rect.sample_solid_angle(x, n, u1, u2);
            REQUIRE(a);
            REQUIRE(b);
            const double v[2] = {dot(n, a->dir) / a->pdf, dot(n, b->dir) / b->pdf};
            for (int k = 0; k < 2; ++k) {
                sum[k] += v[k];
                sum2[k] += v[k] * v[k];
            }
        }
    const double N = m * m;
    const double var_uniform = sum2[0] / N - (sum[0] / N) * (sum[0] / N);
    const double var_warped = sum2[1] / N - (sum[1] / N) * (sum[1] / N);
    INFO("variance of cos θ/pdf: uniform " << var_uniform << ", warped " << var_warped);
    // Both estimate the same projected solid angle (stratified: to ~1e-3).
    CHECK(sum[1] / N == Approx(sum[0] / N).epsilon(1e-2));
    CHECK(var_warped < 0.25 * var_uniform);
}
