#include "sampling/ellipse.h"

#include <algorithm>
#include <cmath>

namespace omis {
namespace {

constexpr double kRimTol = 1e-9;  // relative slack for directions sampled on the rim

// Eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations: on return
// a's diagonal holds the eigenvalues and v's columns the eigenvectors. Jacobi keeps
// the small eigenvalue of the cone matrix of a far, tiny light (next to two of size
// (distance/size)²) to relative precision, which a characteristic polynomial would not.
void jacobi_eigen(double a[3][3], double v[3][3]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) v[i][j] = i == j ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 12; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (off <= 1e-40 * diag) return;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0) continue;
                const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
                const double t = std::copysign(1.0, theta) /
                                 (std::abs(theta) + std::sqrt(theta * theta + 1));
                const double c = 1 / std::sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 3; ++k) {  // a ← a·J
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {  // a ← Jᵀ·a
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
}

// ∫_{−1}^{a} min(b, √(1 − t²)) dt, the area under a disk's upper half capped at b.
double capped_half_disk(double b, double a) {
    auto S = [](double t) { return 0.5 * (t * std::sqrt(std::max(0.0, 1 - t * t)) + std::asin(t)); };
    const double s_m1 = -0.25 * kPi;
    if (b >= 1) return S(a) - s_m1;
    if (b <= 0) return b * (a + 1);
    const double c = std::sqrt(1 - b * b);
    double v = S(std::min(a, -c)) - s_m1;
    if (a > -c) v += b * (std::min(a, c) + c);
    if (a > c) v += S(a) - S(c);
    return v;
}

}  // namespace

// -------------------------------------------------------- spherical ellipse

std::optional<SphericalEllipse> SphericalEllipse::make(const Vec3& x, const Vec3& center,
                                                       const Vec3& axis_a,
                                                       const Vec3& axis_b) {
    const Vec3 to_c = center - x;
    const double dist = length(to_c), la = length(axis_a), lb = length(axis_b);
    if (!(dist > 0 && la > 0 && lb > 0)) return std::nullopt;
    const Vec3 ah = axis_a / la, bh = axis_b / lb, nh = cross(ah, bh);
    const double h = dot(to_c, nh);
    if (!(std::abs(h) > 0)) return std::nullopt;
    // A direction d hits the ellipse iff (r1·d)² + (r2·d)² ≤ (r3·d)² with r3·d of the
    // sign of h: the rows of [axis_a axis_b to_c]⁻¹ scaled by |a||b|. They are written
    // in a frame whose z is the direction to the centre, where r1 and r2 have no z part.
    const Frame f(to_c / dist);
    const Vec3 bl = f.to_local(bh), al = f.to_local(ah), r3 = f.to_local(nh);
    const Vec3 r1 = Vec3{bl.y, -bl.x, 0} * (dist / la);  // (b̂ × ẑ)·dist/|a|
    const Vec3 r2 = Vec3{-al.y, al.x, 0} * (dist / lb);  // (ẑ × â)·dist/|b|
    const double r[3][3] = {{r1.x, r1.y, r1.z}, {r2.x, r2.y, r2.z}, {r3.x, r3.y, r3.z}};
    double m[3][3], v[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m[i][j] = r[2][i] * r[2][j] - r[0][i] * r[0][j] - r[1][i] * r[1][j];
    jacobi_eigen(m, v);
    // One positive eigenvalue (the axis), two negative (the cone's principal planes).
    int p = 0;
    for (int i = 1; i < 3; ++i)
        if (m[i][i] > m[p][p]) p = i;
    const int q1 = (p + 1) % 3, q2 = (p + 2) % 3;
    const double lp = m[p][p], l1 = -m[q1][q1], l2 = -m[q2][q2];
    if (!(lp > 0 && l1 > 0 && l2 > 0)) return std::nullopt;
    Vec3 axis = f.to_world({v[0][p], v[1][p], v[2][p]});
    if (dot(axis, nh) * h < 0) axis = -axis;
    SphericalEllipse s;
    s.axis_ = normalize(axis);
    s.e1_ = normalize(f.to_world({v[0][q1], v[1][q1], v[2][q1]}));
    s.e2_ = cross(s.axis_, s.e1_);
    // tan²(half-angle) = λp/|λq|, so sin² = λp/(λp + |λq|).
    s.sa_ = std::sqrt(lp / (lp + l1));
    s.sb_ = std::sqrt(lp / (lp + l2));
    s.to_center_ = to_c;
    s.normal_ = nh;
    if (!(s.sa_ > 0 && s.sb_ > 0) || !isfinite(s.axis_)) return std::nullopt;
    return s;
}

double SphericalEllipse::sin2_boundary(double lx, double ly) const {
    const double q = lx * lx / (sa_ * sa_) + ly * ly / (sb_ * sb_);
    return q > 0 ? std::min(1.0, (lx * lx + ly * ly) / q) : sa_ * sa_;
}

DirSample SphericalEllipse::sample(double u1, double u2) const {
    // A point on the orthographic ellipse's rim: its azimuth has density ∝ sin²θb(φ),
    // and its distance from the centre is sin θb(φ).
    const double psi = 2 * kPi * u1;
    const double cx = sa_ * std::cos(psi), cy = sb_ * std::sin(psi);
    const double s2 = std::min(1.0, cx * cx + cy * cy);
    const double s = std::sqrt(s2);
    const double omc_b = s2 / (1 + std::sqrt(1 - s2));  // 1 − cos θb, stable
    const double omc = u2 * omc_b;
    const double sin_t = std::sqrt(std::max(0.0, omc * (2 - omc)));
    const Vec3 w = normalize(axis_ * (1 - omc) + (e1_ * cx + e2_ * cy) * (sin_t / s));
    const double den = dot(w, normal_);
    const double t = den != 0 ? dot(to_center_, normal_) / den : 0.0;
    return {w, t > 0 && std::isfinite(t) ? t : length(to_center_)};
}

double SphericalEllipse::pdf(const Vec3& w) const {
    const double lz = dot(w, axis_);
    if (!(lz > 0)) return 0;
    const double lx = dot(w, e1_), ly = dot(w, e2_);
    if (lx * lx / (sa_ * sa_) + ly * ly / (sb_ * sb_) > 1 + kRimTol) return 0;
    const double cos_b = std::sqrt(1 - sin2_boundary(lx, ly));
    return (1 + cos_b) / (2 * kPi * sa_ * sb_);
}

Point2 SphericalEllipse::invert(const Vec3& w) const {
    const double lx = dot(w, e1_), ly = dot(w, e2_), lz = dot(w, axis_);
    double u1 = std::atan2(ly / sb_, lx / sa_) / (2 * kPi);
    if (u1 < 0) u1 += 1;
    const double s2b = sin2_boundary(lx, ly);
    const double omc_b = s2b / (1 + std::sqrt(1 - s2b));
    const double omc = (lx * lx + ly * ly) / (1 + std::max(lz, 0.0));
    return {u1, omc_b > 0 ? std::min(1.0, omc / omc_b) : 0.0};
}

// -------------------------------------------------------------- clipped disk

std::optional<ClippedDisk> ClippedDisk::make(double a0, double a1, double b0, double b1) {
    if (!(b0 < b1 && a0 < a1)) return std::nullopt;
    const double m = std::max({0.0, b0, -b1});  // the box's nearest β to the disk's middle
    if (!(m < 1)) return std::nullopt;
    const double c = std::sqrt(1 - m * m);  // the box meets the disk for |α| < c
    ClippedDisk d;
    d.lo_ = std::max(a0, -c);
    d.hi_ = std::min(a1, c);
    if (!(d.lo_ < d.hi_)) return std::nullopt;
    d.b0_ = b0;
    d.b1_ = b1;
    d.base_ = capped_half_disk(b1, d.lo_) + capped_half_disk(-b0, d.lo_);
    d.total_ = d.cumulative(d.hi_);
    if (!(d.total_ > 0)) return std::nullopt;
    return d;
}

double ClippedDisk::cumulative(double a) const {
    // Chord at α: min(b1, s) − max(b0, −s) = min(b1, s) + min(−b0, s), s = √(1 − α²).
    return capped_half_disk(b1_, a) + capped_half_disk(-b0_, a) - base_;
}

Point2 ClippedDisk::sample(double u1, double u2) const {
    // α: invert the area to its left by Newton steps (the derivative is the chord)
    // kept inside a shrinking bracket.
    const double target = u1 * total_;
    double lo = lo_, hi = hi_, a = lo_ + u1 * (hi_ - lo_);
    for (int it = 0; it < 100; ++it) {
        const double f = cumulative(a) - target;
        if (f > 0) hi = a;
        else lo = a;
        const double s = std::sqrt(std::max(0.0, 1 - a * a));
        const double chord = std::min(b1_, s) - std::max(b0_, -s);
        double next = chord > 0 ? a - f / chord : 0.5 * (lo + hi);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (std::abs(next - a) <= 1e-15 * (hi_ - lo_) || hi - lo <= 1e-15 * (hi_ - lo_)) {
            a = next;
            break;
        }
        a = next;
    }
    const double s = std::sqrt(std::max(0.0, 1 - a * a));
    const double blo = std::max(b0_, -s), bhi = std::min(b1_, s);
    return {a, blo + u2 * std::max(0.0, bhi - blo)};
}

Point2 ClippedDisk::invert(const Point2& p) const {
    const double s = std::sqrt(std::max(0.0, 1 - p.x * p.x));
    const double blo = std::max(b0_, -s), bhi = std::min(b1_, s);
    return {cumulative(p.x) / total_, bhi > blo ? (p.y - blo) / (bhi - blo) : 0.0};
}

bool ClippedDisk::contains(const Point2& p) const {
    const double tol = 1e-9;
    return p.x >= lo_ - tol && p.x <= hi_ + tol && p.y >= b0_ - tol && p.y <= b1_ + tol &&
           p.x * p.x + p.y * p.y <= 1 + 2 * tol;
}

}  // namespace omis
