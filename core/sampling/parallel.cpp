#include "sampling/parallel.h"

#include <algorithm>
#include <cmath>

namespace omis {

namespace {

double cross2(const Point2& a, const Point2& b) { return a.x * b.y - a.y * b.x; }

// Solve off = b1·e1 + b2·e2.
Point2 solve2(const Point2& e1, const Point2& e2, const Point2& off) {
    const double det = cross2(e1, e2);
    return {cross2(off, e2) / det, cross2(e1, off) / det};
}

Vec3 unproject(const Frame& f, double qx, double qy) {
    return normalize(f.to_world({qx, qy, 1.0}));
}

}  // namespace

double ParallelProjection::pdf(const Vec3& w) const {
    const double c = dot(w, frame_.n);
    return c > 0 ? 1.0 / (area_ * c * c * c) : 0.0;
}

std::optional<ParallelPolygon> ParallelPolygon::make(const Vec3& n, const Vec3& to_first,
                                                     const std::vector<Vec3>& offsets) {
    const int count = static_cast<int>(offsets.size());
    if (count != 3 && count != 4) return std::nullopt;
    ParallelPolygon p;
    p.frame_ = Frame(n);
    p.count_ = count;
    const Vec3 y0 = p.frame_.to_local(to_first);
    for (int i = 0; i < count; ++i) {
        const Vec3 yi = to_first + offsets[i];
        if (!(dot(yi, n) > kParallelHorizonEps * length(yi))) return std::nullopt;
    }
    p.q0_ = {y0.x / y0.z, y0.y / y0.z};
    for (int i = 0; i < count; ++i) {
        const Vec3 e = p.frame_.to_local(offsets[i] - offsets[0]);
        const double zi = y0.z + e.z;
        p.dq_[i] = {(e.x * y0.z - y0.x * e.z) / (y0.z * zi), (e.y * y0.z - y0.y * e.z) / (y0.z * zi)};
    }
    p.a1_ = 0.5 * std::abs(cross2(p.dq_[1], p.dq_[2]));
    const double a2 = count == 4 ? 0.5 * std::abs(cross2(p.dq_[2], p.dq_[3])) : 0.0;
    p.area_ = p.a1_ + a2;
    if (!(p.area_ > 0) || !std::isfinite(p.area_)) return std::nullopt;
    return p;
}

Vec3 ParallelPolygon::sample(double u1, double u2) const {
    double v = u1 * area_;
    int j = 1;
    if (v < a1_ || count_ == 3) {
        v = std::min(v / a1_, 1.0);
    } else {
        v = std::min((v - a1_) / (area_ - a1_), 1.0);
        j = 2;
    }
    const Point2 b = sample_uniform_triangle(v, u2);
    const Point2& e1 = dq_[j];
    const Point2& e2 = dq_[j + 1];
    return unproject(frame_, q0_.x + b.x * e1.x + b.y * e2.x, q0_.y + b.x * e1.y + b.y * e2.y);
}

Point2 ParallelPolygon::invert(const Vec3& w) const {
    const Vec3 l = frame_.to_local(w);
    const Point2 off{l.x / l.z - q0_.x, l.y / l.z - q0_.y};
    Point2 b = solve2(dq_[1], dq_[2], off);
    if (count_ == 3 || b.x >= 0) {  // tri 1 lies on the dq1 side of the diagonal
        b = {std::max(b.x, 0.0), std::max(b.y, 0.0)};
        const Point2 u = invert_uniform_triangle(b);
        return {std::clamp(u.x * a1_ / area_, 0.0, 1.0), u.y};
    }
    b = solve2(dq_[2], dq_[3], off);
    b = {std::max(b.x, 0.0), std::max(b.y, 0.0)};
    const Point2 u = invert_uniform_triangle(b);
    return {std::clamp((a1_ + u.x * (area_ - a1_)) / area_, 0.0, 1.0), u.y};
}

std::optional<ParallelEllipse> ParallelEllipse::make(const Vec3& n, const Vec3& to_center,
                                                     const Vec3& axis_a, const Vec3& axis_b) {
    ParallelEllipse p;
    p.frame_ = Frame(n);
    const Vec3 c = p.frame_.to_local(to_center);
    const Vec3 a = p.frame_.to_local(axis_a);
    const Vec3 b = p.frame_.to_local(axis_b);
    const double lowest = c.z - std::hypot(a.z, b.z);  // min over the rim of (y − x)·n
    if (!(lowest > kParallelHorizonEps * (length(c) + length(a) + length(b)))) return std::nullopt;
    // Offsets from the projected centre: Δq = (K p)/(c_n (c_n + p_n)), K linear.
    const double c2 = c.z * c.z;
    p.g1_ = {(a.x * c.z - c.x * a.z) / c2, (a.y * c.z - c.y * a.z) / c2};
    p.g2_ = {(b.x * c.z - c.x * b.z) / c2, (b.y * c.z - c.y * b.z) / c2};
    p.qc_ = {c.x / c.z, c.y / c.z};
    const Point2 rho{a.z / c.z, b.z / c.z};
    const double e = std::hypot(rho.x, rho.y);
    if (!(e < 1)) return std::nullopt;
    p.rho_dir_ = e > 0 ? Point2{rho.x / e, rho.y / e} : Point2{1, 0};
    const double one_m_e2 = (1 - e) * (1 + e);
    p.az_ = 1.0 / one_m_e2;
    p.bz_ = 1.0 / std::sqrt(one_m_e2);
    p.center_z_ = {-e * p.az_ * p.rho_dir_.x, -e * p.az_ * p.rho_dir_.y};
    p.area_ = kPi * std::abs(cross2(p.g1_, p.g2_)) * p.az_ * p.bz_;
    if (!(p.area_ > 0) || !std::isfinite(p.area_)) return std::nullopt;
    return p;
}

Vec3 ParallelEllipse::sample(double u1, double u2) const {
    const Point2 d = sample_uniform_disk(u1, u2);
    const double s = az_ * d.x, t = bz_ * d.y;
    const Point2 z{center_z_.x + rho_dir_.x * s - rho_dir_.y * t,
                   center_z_.y + rho_dir_.y * s + rho_dir_.x * t};
    return unproject(frame_, qc_.x + g1_.x * z.x + g2_.x * z.y, qc_.y + g1_.y * z.x + g2_.y * z.y);
}

Point2 ParallelEllipse::invert(const Vec3& w) const {
    const Vec3 l = frame_.to_local(w);
    const Point2 off{l.x / l.z - qc_.x, l.y / l.z - qc_.y};
    const Point2 z = solve2(g1_, g2_, off);
    const Point2 zz{z.x - center_z_.x, z.y - center_z_.y};
    const Point2 d{(zz.x * rho_dir_.x + zz.y * rho_dir_.y) / az_,
                   (-zz.x * rho_dir_.y + zz.y * rho_dir_.x) / bz_};
    return invert_uniform_disk(d);
}

}  // namespace omis
