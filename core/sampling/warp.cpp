#include "sampling/warp.h"

#include <algorithm>
#include <cmath>

namespace omis {

namespace {

// Shirley and Chiu's concentric map from the square to the unit disk: it
// keeps areas (density 1/π) and, unlike the polar map, keeps strata compact —
// a stratified or low-discrepancy point set stays well spread on the disk, so
// every warp built on it converges faster with the same samples (Cycles and
// pbrt-v4 draw disks and cosine directions this way too).
Point2 concentric_disk(double u1, double u2) {
    const double a = 2.0 * u1 - 1.0, b = 2.0 * u2 - 1.0;
    if (a == 0 && b == 0) return {0, 0};
    double r, phi;
    if (std::abs(a) > std::abs(b)) {
        r = a;
        phi = 0.25 * kPi * (b / a);
    } else {
        r = b;
        phi = 0.5 * kPi - 0.25 * kPi * (a / b);
    }
    return {r * std::cos(phi), r * std::sin(phi)};
}

// The square point concentric_disk maps to p (|p| ≤ 1).
Point2 invert_concentric_disk(const Point2& p) {
    const double r = std::min(std::hypot(p.x, p.y), 1.0);
    if (r == 0) return {0.5, 0.5};
    const double phi = std::atan2(p.y, p.x);  // (−π, π]
    double a, b;
    if (std::abs(p.x) >= std::abs(p.y)) {  // the wedges around ±x: |b| ≤ |a| = r
        a = p.x >= 0 ? r : -r;
        const double theta = p.x >= 0 ? phi : (phi > 0 ? phi - kPi : phi + kPi);
        b = a * theta / (0.25 * kPi);
    } else {  // around ±y: |a| < |b| = r
        b = p.y >= 0 ? r : -r;
        const double theta = p.y >= 0 ? phi : phi + kPi;
        a = b * (0.5 * kPi - theta) / (0.25 * kPi);
    }
    auto unit = [](double t) { return std::clamp(0.5 * (t + 1.0), 0.0, 1.0); };
    return {unit(a), unit(b)};
}

}  // namespace

Vec3 sample_cosine_hemisphere(double u1, double u2) {
    const Point2 d = concentric_disk(u1, u2);  // Malley: lift the uniform disk
    return {d.x, d.y, std::sqrt(std::max(0.0, 1.0 - d.x * d.x - d.y * d.y))};
}

double pdf_cosine_hemisphere(const Vec3& w) { return std::max(0.0, w.z) * kInvPi; }

Point2 invert_cosine_hemisphere(const Vec3& w) { return invert_concentric_disk({w.x, w.y}); }

Cone Cone::from_half_angle(const Vec3& axis, double half_angle) {
    const double s = std::sin(0.5 * half_angle);
    return {normalize(axis), 2.0 * s * s};
}

Cone Cone::facing_disk(const Vec3& x, const Vec3& center, double radius) {
    const Vec3 dv = center - x;
    const double d = length(dv);
    const double hyp = std::hypot(d, radius);
    // 1 − d/hyp without cancellation.
    return {dv / d, radius * radius / (hyp * (hyp + d))};
}

Cone Cone::around_sphere(const Vec3& x, const Vec3& center, double radius) {
    const Vec3 dv = center - x;
    const double d = length(dv);
    const double s2 = std::min(1.0, (radius / d) * (radius / d));  // sin²θmax
    // 1 − cos θmax = sin²/(1 + cos) without cancellation.
    return {dv / d, s2 / (1.0 + std::sqrt(1.0 - s2))};
}

// The uniform disk (concentric) lifted to the cone: a disk point at radius ρ
// goes to 1 − cos θ = ρ²(1 − cos θmax) along its own azimuth, which maps equal
// disk areas to equal solid angles.
Vec3 Cone::sample(double u1, double u2) const {
    const Point2 d = concentric_disk(u1, u2);
    const double rho2 = d.x * d.x + d.y * d.y;
    const double h = rho2 * one_minus_cos;  // 1 − cos θ
    const double sin_t = std::sqrt(std::max(0.0, h * (2.0 - h)));
    const double scale = rho2 > 0 ? sin_t / std::sqrt(rho2) : 0.0;
    const Frame f(axis);
    return f.to_world({scale * d.x, scale * d.y, 1.0 - h});
}

bool Cone::contains(const Vec3& w) const {
    const Vec3 l = Frame(axis).to_local(w);
    if (l.z <= 0 && one_minus_cos < 1.0) return false;
    // 1 − cos θ = sin²θ/(1 + cos θ) keeps precision for tiny angles.
    const double s2 = l.x * l.x + l.y * l.y;
    const double h = l.z > 0 ? s2 / (1.0 + l.z) : 1.0 - l.z;
    return h <= one_minus_cos * (1.0 + 1e-9);
}

double Cone::pdf(const Vec3& w) const {
    return contains(w) ? 1.0 / solid_angle() : 0.0;
}

Point2 Cone::invert(const Vec3& w) const {
    const Vec3 l = Frame(axis).to_local(w);
    const double s2 = l.x * l.x + l.y * l.y;
    const double h = l.z > 0 ? s2 / (1.0 + l.z) : 1.0 - l.z;
    const double rho = std::sqrt(std::clamp(h / one_minus_cos, 0.0, 1.0));
    const double s = std::sqrt(s2);
    if (!(s > 0)) return invert_concentric_disk({0, 0});
    return invert_concentric_disk({rho * l.x / s, rho * l.y / s});
}

Point2 sample_uniform_triangle(double u1, double u2) {
    const double su = std::sqrt(u1);
    return {su * (1.0 - u2), su * u2};
}

Point2 invert_uniform_triangle(const Point2& b) {
    const double su = b.x + b.y;
    return {su * su, su > 0 ? std::clamp(b.y / su, 0.0, 1.0) : 0.0};
}

namespace {

// Density ∝ lerp(x, a, b) on [0,1) (a, b ≥ 0, a + b > 0), inverted in closed form
// in the form that keeps precision when a ≈ b.
double sample_linear(double u, double a, double b) {
    if (u == 0 && a == 0) return 0;
    const double x = u * (a + b) / (a + std::sqrt((1 - u) * a * a + u * b * b));
    return std::min(x, 1.0 - 1e-16);
}

}  // namespace

namespace {

// Density ∝ the piecewise-linear function through v[0..g] at 0, 1/g, …, 1:
// the segment by its trapezoid mass, then the linear piece within it.
double sample_piecewise_linear(double u, const double* v, int g) {
    double total = 0;
    for (int i = 0; i < g; ++i) total += v[i] + v[i + 1];
    double below = 0;
    for (int i = 0; i < g; ++i) {
        const double mass = (v[i] + v[i + 1]) / total;
        if (u < below + mass || i == g - 1) {
            const double t = std::clamp((u - below) / mass, 0.0, 1.0);
            return std::min((i + sample_linear(t, v[i], v[i + 1])) / g, 1.0 - 1e-16);
        }
        below += mass;
    }
    return 0;
}

// The node weights' bilinear interpolation at p, and their integral over [0,1)².
double interpolate(const Point2& p, const double* w, int g) {
    const int i = std::min(g - 1, int(p.x * g)), j = std::min(g - 1, int(p.y * g));
    const double s = p.x * g - i, t = p.y * g - j;
    const int n = g + 1;
    return (1 - s) * (1 - t) * w[j * n + i] + s * (1 - t) * w[j * n + i + 1] +
           (1 - s) * t * w[(j + 1) * n + i] + s * t * w[(j + 1) * n + i + 1];
}

double integral(const double* w, int g) {
    const int n = g + 1;
    double sum = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            sum += w[j * n + i] * ((i == 0 || i == g) ? 0.5 : 1.0) * ((j == 0 || j == g) ? 0.5 : 1.0);
    return sum / (double(g) * g);
}

constexpr int kMaxPatches = 4;

}  // namespace

Point2 sample_piecewise_bilinear(double u1, double u2, const double* w, int g) {
    g = std::clamp(g, 1, kMaxPatches);
    if (g == 1) {
        // One patch (the cosine warp's): the general path's arithmetic
        // without its loops, bit for bit (its segment masses are exactly 1).
        const double y = std::min(sample_linear(u2, 0.5 * w[0] + 0.5 * w[1],
                                                0.5 * w[2] + 0.5 * w[3]), 1.0 - 1e-16);
        const double a = (1 - y) * w[0] + y * w[2], b = (1 - y) * w[1] + y * w[3];
        return {std::min(sample_linear(u1, a, b), 1.0 - 1e-16), y};
    }
    const int n = g + 1;
    // Marginal in y at the nodes: the trapezoid rule in x is exact for the
    // piecewise-linear rows.
    double marginal[kMaxPatches + 1], row[kMaxPatches + 1];
    for (int j = 0; j < n; ++j) {
        marginal[j] = 0;
        for (int i = 0; i < n; ++i) marginal[j] += w[j * n + i] * ((i == 0 || i == g) ? 0.5 : 1.0);
    }
    const double y = sample_piecewise_linear(u2, marginal, g);
    const int j = std::min(g - 1, int(y * g));
    const double t = y * g - j;
    for (int i = 0; i < n; ++i) row[i] = (1 - t) * w[j * n + i] + t * w[(j + 1) * n + i];
    return {sample_piecewise_linear(u1, row, g), y};
}

double pdf_piecewise_bilinear(const Point2& p, const double* w, int g) {
    g = std::clamp(g, 1, kMaxPatches);
    if (g == 1) {
        // One patch (the cosine warp's, at every solid-angle sample and
        // density): integral without its loops, bit for bit (each node weighs
        // 0.5·0.5 exactly, the sum is over 1·1).
        return interpolate(p, w, 1) / (w[0] * 0.25 + w[1] * 0.25 + w[2] * 0.25 + w[3] * 0.25);
    }
    return interpolate(p, w, g) / integral(w, g);
}

Point2 sample_uniform_disk(double u1, double u2) { return concentric_disk(u1, u2); }

Point2 invert_uniform_disk(const Point2& p) { return invert_concentric_disk(p); }

}  // namespace omis
