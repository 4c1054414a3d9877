#include "sampling/ellipse.h"

#include <algorithm>
#include <cmath>

namespace omis {
namespace {

constexpr double kRimTol = 1e-9;  // relative slack for directions sampled on the rim
// Absolute slack (radians) of the rim test: a unit vector's components carry a few
// ulps, which is a large part of a cone's half-angle 1e-9 thick.
constexpr double kDirectionUlps = 1e-15;

// Boosts a spacelike column u and the timelike column v of the cone's generator
// apart (u·v = 0 after): the Lorentz boost in their plane, which maps the round cone
// onto itself, of rapidity ½ ln(|m|/|p|), p = u + v, m = u − v. Its cosh and sinh
// from those lengths, (|p| + |m|)/(2√(|p||m|)) and −2u·v/((|p| + |m|)√(|p||m|)), take
// no difference of nearly equal numbers. Where u ≈ v (x beside the rim) the boost is
// strong and loses ~ε·size/(x's distance to the rim), the cone's own sensitivity to x
// there (1e-9 beside a rim and off the plane: sin α within 2e-9 of mpmath's).
bool boost_apart(Vec3& u, Vec3& v) {
    const double lp = length(u + v), lm = length(u - v);
    const double root = std::sqrt(lp) * std::sqrt(lm);
    if (!(root > 0)) return false;
    const double ch = (lp + lm) / (2 * root), sh = -2 * dot(u, v) / ((lp + lm) * root);
    const Vec3 u0 = u;
    u = u0 * ch + v * sh;
    v = u0 * sh + v * ch;
    return true;
}

// Rotates two spacelike columns apart (u·v = 0 after): one-sided Jacobi.
void rotate_apart(Vec3& u, Vec3& v) {
    const double g = dot(u, v);
    if (g == 0) return;
    const double z = (dot(v, v) - dot(u, u)) / (2 * g);
    const double t = std::copysign(1.0, z) / (std::abs(z) + std::sqrt(z * z + 1));
    const double c = 1 / std::sqrt(t * t + 1), s = c * t;
    const Vec3 u0 = u;
    u = u0 * c - v * s;
    v = u0 * s + v * c;
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
    const Vec3 nh = cross(normalize(axis_a), normalize(axis_b));  // axes perpendicular
    const double h = dot(to_c, nh);
    if (!(std::abs(h) > 0) || !isfinite(nh)) return std::nullopt;
    // The directions to the ellipse are g·(α, β, 1), α² + β² ≤ 1, for the generator
    // g = [axis_a axis_b to_c]: the round cone k₁² + k₂² ≤ k₃² mapped by g. Lorentz
    // transforms of the round cone (rotations of the first two columns, boosts of
    // either with the third) keep the set; once the columns are orthogonal, the
    // third is the cone's axis and the first two its principal directions with
    // tan(half-angle) = |g_i|/|g₃|. Working on the columns (one-sided, hyperbolic
    // Jacobi) rather than on the cone's matrix keeps the precision a matrix of
    // their products would square away: seen edge-on from 1e-9 off its plane, the
    // cone is 1e-9 thick, its matrix's eigenvalues 1e-18 apart in relative size.
    Vec3 g[3] = {axis_a, axis_b, to_c};
    constexpr double kOrthogonal = 1e-14;  // |cos| between columns taken as 0
    for (int sweep = 0;; ++sweep) {
        bool apart = true;
        for (const auto& [i, j] : {std::pair{0, 2}, std::pair{1, 2}, std::pair{0, 1}}) {
            const double gij = dot(g[i], g[j]);
            if (gij * gij <= kOrthogonal * kOrthogonal * dot(g[i], g[i]) * dot(g[j], g[j])) continue;
            apart = false;
            if (j == 1) rotate_apart(g[0], g[1]);
            else if (!boost_apart(g[i], g[2])) return std::nullopt;
        }
        if (apart) break;
        if (sweep == 30) return std::nullopt;
    }
    const double q0 = dot(g[0], g[0]), q1 = dot(g[1], g[1]), q2 = dot(g[2], g[2]);
    SphericalEllipse s;
    s.axis_ = g[2] / std::sqrt(q2);
    // The boosts keep the cone's nappe: the axis points to the light's side.
    if (!(dot(s.axis_, nh) * h > 0)) return std::nullopt;
    s.e1_ = normalize(g[0] - s.axis_ * dot(g[0], s.axis_));
    s.e2_ = cross(s.axis_, s.e1_);
    s.sa_ = std::sqrt(q0 / (q0 + q2));
    s.sb_ = std::sqrt(q1 / (q1 + q2));
    s.ca_ = std::sqrt(q2 / (q0 + q2));
    s.cb_ = std::sqrt(q2 / (q1 + q2));
    s.to_center_ = to_c;
    s.normal_ = nh;
    const double slack = 1 + kRimTol + kDirectionUlps / std::min(s.sa_, s.sb_);
    s.rim_slack_ = slack * slack;
    if (!(s.sa_ > 0 && s.sb_ > 0) || !isfinite(s.axis_) || !isfinite(s.e1_)) return std::nullopt;
    return s;
}

SphericalEllipse::Rim SphericalEllipse::rim(double cos_psi, double sin_psi) const {
    // The rim point (sin α cos ψ, sin β sin ψ) of the orthographic image; cos²θb from
    // the half-angles' cosines, not 1 − sin²θb (which loses a cone near a hemisphere).
    const double cx = sa_ * cos_psi, cy = sb_ * sin_psi;
    const double kx = ca_ * cos_psi, ky = cb_ * sin_psi;
    return {cx, cy, cx * cx + cy * cy, std::sqrt(kx * kx + ky * ky)};
}

SphericalEllipse::Rim SphericalEllipse::rim_toward(double lx, double ly) const {
    // (cos ψ, sin ψ) ∝ (lx/sin α, ly/sin β), scaled by sin α sin β (no overflow).
    const double px = lx * sb_, py = ly * sa_, r = std::sqrt(px * px + py * py);
    return r > 0 ? rim(px / r, py / r) : rim(1, 0);
}

DirSample SphericalEllipse::sample(double u1, double u2) const {
    // A point on the orthographic ellipse's rim: its azimuth has density ∝ sin²θb(φ),
    // and its distance from the centre is sin θb(φ).
    const double psi = 2 * kPi * u1;
    const Rim b = rim(std::cos(psi), std::sin(psi));
    const double s = std::sqrt(b.sin2);
    const double omc_b = b.sin2 / (1 + b.cos);  // 1 − cos θb, stable
    const double omc = u2 * omc_b;
    const double sin_t = std::sqrt(std::max(0.0, omc * (2 - omc)));
    const Vec3 w = normalize(axis_ * (1 - omc) + (e1_ * b.x + e2_ * b.y) * (sin_t / s));
    const double den = dot(w, normal_);
    const double t = den != 0 ? dot(to_center_, normal_) / den : 0.0;
    return {w, t > 0 && std::isfinite(t) ? t : length(to_center_)};
}

double SphericalEllipse::pdf(const Vec3& w) const {
    const double lz = dot(w, axis_);
    if (!(lz > 0)) return 0;
    const double lx = dot(w, e1_), ly = dot(w, e2_);
    if (lx * lx / (sa_ * sa_) + ly * ly / (sb_ * sb_) > rim_slack_) return 0;
    return (1 + rim_toward(lx, ly).cos) / (2 * kPi * sa_ * sb_);
}

Point2 SphericalEllipse::invert(const Vec3& w) const {
    const double lx = dot(w, e1_), ly = dot(w, e2_), lz = dot(w, axis_);
    double u1 = std::atan2(ly / sb_, lx / sa_) / (2 * kPi);
    if (u1 < 0) u1 += 1;
    const Rim b = rim_toward(lx, ly);
    const double omc_b = b.sin2 / (1 + b.cos);
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
