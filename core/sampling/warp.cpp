#include "sampling/warp.h"

#include <algorithm>
#include <cmath>

namespace omis {

namespace {

// Azimuth in [0,1): the u2 coordinate of polar warps.
double azimuth01(double y, double x) {
    double a = std::atan2(y, x) / (2.0 * kPi);
    if (a < 0) a += 1.0;
    return a >= 1.0 ? 0.0 : a;
}

}  // namespace

Vec3 sample_cosine_hemisphere(double u1, double u2) {
    const double r = std::sqrt(u1);
    const double phi = 2.0 * kPi * u2;
    return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - u1))};
}

double pdf_cosine_hemisphere(const Vec3& w) { return std::max(0.0, w.z) * kInvPi; }

Point2 invert_cosine_hemisphere(const Vec3& w) {
    return {std::min(w.x * w.x + w.y * w.y, 1.0), azimuth01(w.y, w.x)};
}

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

Vec3 Cone::sample(double u1, double u2) const {
    const double h = u1 * one_minus_cos;  // 1 − cos θ
    const double sin_t = std::sqrt(std::max(0.0, h * (2.0 - h)));
    const double phi = 2.0 * kPi * u2;
    const Frame f(axis);
    return f.to_world({sin_t * std::cos(phi), sin_t * std::sin(phi), 1.0 - h});
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
    return {std::clamp(h / one_minus_cos, 0.0, 1.0), azimuth01(l.y, l.x)};
}

Point2 sample_uniform_triangle(double u1, double u2) {
    const double su = std::sqrt(u1);
    return {su * (1.0 - u2), su * u2};
}

Point2 invert_uniform_triangle(const Point2& b) {
    const double su = b.x + b.y;
    return {su * su, su > 0 ? std::clamp(b.y / su, 0.0, 1.0) : 0.0};
}

Point2 sample_uniform_disk(double u1, double u2) {
    const double r = std::sqrt(u1);
    const double phi = 2.0 * kPi * u2;
    return {r * std::cos(phi), r * std::sin(phi)};
}

Point2 invert_uniform_disk(const Point2& p) {
    return {std::min(p.x * p.x + p.y * p.y, 1.0), azimuth01(p.y, p.x)};
}

}  // namespace omis
