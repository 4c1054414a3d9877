#include "sampling/spherical.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace omis {

namespace {
constexpr double kHitTol = 1e-7;  // relative slack of hit tests for samples on an edge
}

double triangle_solid_angle(const Vec3& a, const Vec3& e1, const Vec3& e2) {
    const Vec3 b = a + e1, c = a + e2;
    const double la = length(a), lb = length(b), lc = length(c);
    // a·(b×c) = a·(e1×e2): the triple product of short edges, no cancellation.
    const double num = std::abs(dot(a, cross(e1, e2)));
    const double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    return 2.0 * std::atan2(num, den);
}

double polygon_solid_angle(const Vec3& to_first, const std::vector<Vec3>& offsets) {
    double sum = 0;
    const Vec3 a = to_first + offsets[0];
    for (size_t i = 1; i + 1 < offsets.size(); ++i)
        sum += triangle_solid_angle(a, offsets[i] - offsets[0], offsets[i + 1] - offsets[0]);
    return sum;
}

// ---------------------------------------------------------------- rectangle

std::optional<SphericalRect> SphericalRect::make(const Vec3& x, const Vec3& corner,
                                                 const Vec3& edge_u, const Vec3& edge_v) {
    SphericalRect r;
    r.W_ = length(edge_u);
    r.H_ = length(edge_v);
    if (!(r.W_ > 0) || !(r.H_ > 0)) return std::nullopt;
    if (std::abs(dot(edge_u, edge_v)) > 1e-9 * r.W_ * r.H_) return std::nullopt;
    r.ex_ = edge_u / r.W_;
    r.ey_ = edge_v / r.H_;
    r.ez_ = cross(r.ex_, r.ey_);
    const Vec3 d = corner - x;
    double zc = dot(d, r.ez_);
    if (zc > 0) {
        r.ez_ = -r.ez_;
        zc = -zc;
    }
    r.z_ = -zc;
    if (!(r.z_ > 0)) return std::nullopt;
    r.x0_ = dot(d, r.ex_);
    r.y0_ = dot(d, r.ey_);
    r.y1_ = r.y0_ + r.H_;
    r.dphi_ = std::atan2(r.z_ * r.W_, r.x0_ * (r.x0_ + r.W_) + r.z_ * r.z_);
    r.r0_ = std::sqrt(r.x0_ * r.x0_ + r.z_ * r.z_);
    r.cos_phi0_ = r.z_ / r.r0_;  // φ0 = atan2(x0, z): the azimuth of the edge at x0
    r.sin_phi0_ = r.x0_ / r.r0_;
    const Vec3 near0{r.x0_, r.y0_, -r.z_}, near1{r.x0_, r.y1_, -r.z_};  // sub_solid_angle's a, d
    r.la_ = length(near0);
    r.ld_ = length(near1);
    r.ad_ = dot(near0, near1);
    r.omega_ = r.sub_solid_angle(r.W_, r.far_lengths_);
    if (!(r.omega_ > 0) || !std::isfinite(r.omega_) || !(r.dphi_ > 0)) return std::nullopt;
    // The inverse δ(u1)'s slopes at both ends (in units of dphi per u1):
    // Ω/(dphi · dΩ/dφ), with dΩ/dφ = h1 − h0 at the edges x0 and x0 + W.
    // Capped at 3, the Hermite cubic through them is monotone (Fritsch &
    // Carlson), so the first guess stays inside [0, dphi]; an edge seen
    // edge-on (dΩ/dφ = 0: an infinite slope, or 0/0) takes the cap.
    const double slope_near = r.dsolid_angle_dphi(r.la_, r.ld_);
    const double slope_far = r.dsolid_angle_dphi(r.far_lengths_[0], r.far_lengths_[1]);
    const double scale = r.omega_ / r.dphi_;
    r.guess_slope0_ = std::min(3.0, scale / slope_near);
    r.guess_slope1_ = std::min(3.0, scale / slope_far);
    return r;
}

double SphericalRect::width_at(double delta, double sin_delta, double c) const {
    if (delta >= dphi_) return W_;
    if (!(c > 0)) return W_;
    // z (tan φ − tan φ0) = sin δ · r0 / cos φ: no difference of two tangents.
    return std::clamp(sin_delta * r0_ / c, 0.0, W_);
}

void SphericalRect::rotate(double delta, double& sin_delta, double& cos_phi,
                           double& sin_phi) const {
    sin_delta = std::sin(delta);
    turn(std::cos(delta), sin_delta, cos_phi, sin_phi);
}

void SphericalRect::turn(double cos_delta, double sin_delta, double& cos_phi,
                         double& sin_phi) const {
    cos_phi = cos_phi0_ * cos_delta - sin_phi0_ * sin_delta;
    sin_phi = sin_phi0_ * cos_delta + cos_phi0_ * sin_delta;
}

namespace {

// cos and sin of δ + step (= next) from those of δ. Newton's steps after the
// first are tiny: there the rotation by `step` as its Taylor series (to step⁵
// in sin, step⁴ in cos: the first terms left out are below 1e-20 for
// |step| ≤ 1e-3) replaces a sincos.
void advance_angle(double step, double next, double& cos_a, double& sin_a) {
    if (!(std::abs(step) <= 1e-3)) {
        cos_a = std::cos(next);
        sin_a = std::sin(next);
        return;
    }
    const double s2 = step * step;
    const double sin_step = step * (1.0 - s2 / 6.0 * (1.0 - s2 / 20.0));
    const double cos_step = 1.0 - s2 / 2.0 * (1.0 - s2 / 12.0);
    const double c = cos_a * cos_step - sin_a * sin_step;
    sin_a = sin_a * cos_step + cos_a * sin_step;
    cos_a = c;
}

}  // namespace

double SphericalRect::sub_solid_angle(double w, double* bc_lengths) const {
    double x, y;
    half_angle_vector(w, x, y, bc_lengths);
    return 2.0 * std::atan2(y, x);
}

void SphericalRect::half_angle_vector(double w, double& x, double& y, double* bc_lengths) const {
    // a and d (the edge at x0) are the same at every w: their lengths and a·d
    // are kept (make), as Newton evaluates this a few times per sample.
    const Vec3 a{x0_, y0_, -z_}, b{x0_ + w, y0_, -z_}, c{x0_ + w, y1_, -z_}, d{x0_, y1_, -z_};
    const double la = la_, lb = length(b), lc = length(c), ld = ld_;
    const double num = z_ * w * H_;
    const double den1 = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    const double den2 = la * lc * ld + dot(a, c) * ld + ad_ * lc + dot(c, d) * la;
    // The two triangles' half-angles θ1 + θ2 (each in [0, π), their sum Ω/2 <
    // π) as one atan2: tan(θ1 + θ2) = num (den1 + den2) / (den1 den2 − num²),
    // no subtraction of angles (one atan2 instead of two per Newton step).
    // A sum near π (Ω near 2π) may round den1 + den2 below 0: clamped, it
    // gives π.
    y = std::max(0.0, num * (den1 + den2));
    x = den1 * den2 - num * num;
    if (bc_lengths) {
        bc_lengths[0] = lb;
        bc_lengths[1] = lc;
    }
}

double SphericalRect::first_guess(double u1) const {
    // The cubic Hermite through δ(0) = 0 and δ(1) = dphi with the slopes of
    // make(): exact to third order for small rectangles, where the guess
    // u1·dphi was off by the slopes' difference.
    const double t = u1, t2 = t * t, t3 = t2 * t;
    const double f = (t3 - 2 * t2 + t) * guess_slope0_ + (3 * t2 - 2 * t3) +
                     (t3 - t2) * guess_slope1_;
    return std::clamp(f, 0.0, 1.0) * dphi_;
}

double SphericalRect::h_at(double cos_phi, double y) const {
    return y * cos_phi / std::sqrt(z_ * z_ + y * y * cos_phi * cos_phi);
}

DirSample SphericalRect::sample(double u1, double u2) const {
    // Newton on g = Ω(δ) − target, with g taken as 2 sin(g/2) from the
    // half-angle vector (x, y) of Ω(δ) and the target's (cos, sin): the same
    // sign and root and the same value to second order, without an atan2 per
    // step (|g/2| < π always: Ω and the target lie in [0, 2π)).
    const double target = u1 * omega_;
    const double ct = std::cos(0.5 * target), st = std::sin(0.5 * target);
    double lo = 0, hi = dphi_, delta = first_guess(u1);
    double cd = std::cos(delta), sd = std::sin(delta);
    for (int it = 0; it < 100; ++it) {
        double c, unused_sin;
        turn(cd, sd, c, unused_sin);
        double x, y, bc[2];
        half_angle_vector(width_at(delta, sd, c), x, y, bc);
        const double dg = dsolid_angle_dphi(bc[0], bc[1]);
        const double r = std::sqrt(x * x + y * y);
        const double g = r > 0 ? 2.0 * (y * ct - x * st) / r : -target;
        if (g == 0) break;
        (g < 0 ? lo : hi) = delta;
        double next = delta - g / dg;
        // Where δ already misses u1 by at most 1e-9 (|g| ≤ 1e-9 Ω), the
        // Newton step from it is taken without another evaluation: 3.0
        // instead of 3.6 evaluations (a cos and an atan2 each) per sample,
        // 0.8× the time of a draw (worst u1 error unchanged, 2e-10), and where
        // Newton's quadratic convergence fails u1 is still met to 1e-9 (a
        // rectangle edge-on 1e-7 off its plane: the sampler test's inversion
        // check). From first_guess, 2.0 evaluations per sample on the race's
        // square light (2.8 from u1·dphi).
        const bool newton = next > lo && next < hi;
        if (!newton) next = 0.5 * (lo + hi);
        const bool done = (newton && std::abs(g) <= 1e-9 * omega_) ||
                          std::abs(next - delta) <= 1e-13 * dphi_ || hi - lo <= 1e-15 * dphi_;
        advance_angle(next - delta, next, cd, sd);
        delta = next;
        if (done) break;
    }
    double cp, sp;
    turn(cd, sd, cp, sp);
    const double h0 = h_at(cp, y0_), h1 = h_at(cp, y1_);
    const double hv = std::clamp(h0 + u2 * (h1 - h0), -1.0, 1.0);
    const double cv = std::sqrt(std::max(0.0, (1.0 - hv) * (1.0 + hv)));
    DirSample s;
    s.dir = ex_ * (cv * sp) + ey_ * hv - ez_ * (cv * cp);
    const double down = cv * cp;
    s.dist = down > 0 ? z_ / down : std::numeric_limits<double>::max();
    return s;
}

Vec3 SphericalRect::corner_direction(int i, int j) const {
    // u1 = i puts φ on the edge x0 + i·W, u2 = j puts h at y0 + j·H.
    // Its length, kept by make(), is the same in the rectangle's frame.
    const double len = i ? far_lengths_[j] : (j ? ld_ : la_);
    return (ex_ * (x0_ + i * W_) + ey_ * (j ? y1_ : y0_) - ez_ * z_) / len;
}

double SphericalRect::pdf(const Vec3& w) const {
    const double lz = dot(w, ez_);
    if (!(lz < 0)) return 0;
    const double t = z_ / -lz;
    const double xu = dot(w, ex_) * t - x0_, yv = dot(w, ey_) * t - y0_;
    const bool in = xu >= -kHitTol * W_ && xu <= (1 + kHitTol) * W_ && yv >= -kHitTol * H_ &&
                    yv <= (1 + kHitTol) * H_;
    return in ? 1.0 / omega_ : 0.0;
}

Point2 SphericalRect::invert(const Vec3& w) const {
    const double lx = dot(w, ex_), ly = dot(w, ey_), lz = dot(w, ez_);
    // φ − φ0 from the direction's azimuth (sin, cos) ∝ (lx, −lz) rotated by −φ0.
    const double delta = std::clamp(std::atan2(lx * cos_phi0_ + lz * sin_phi0_,
                                               lx * sin_phi0_ - lz * cos_phi0_),
                                    0.0, dphi_);
    double sd, cd, unused_sin;
    rotate(delta, sd, cd, unused_sin);
    const double u1 = sub_solid_angle(width_at(delta, sd, cd)) / omega_;
    const double c = -lz / std::hypot(lx, lz);  // cos φ
    const double h0 = h_at(c, y0_), h1 = h_at(c, y1_);
    return {std::clamp(u1, 0.0, 1.0), std::clamp((ly - h0) / (h1 - h0), 0.0, 1.0)};
}

// ----------------------------------------------------------------- triangle

std::optional<SphericalTriangle> SphericalTriangle::make(const Vec3& x, const Vec3& p0,
                                                         const Vec3& p1, const Vec3& p2) {
    SphericalTriangle s;
    s.to_p0_ = p0 - x;
    s.edge01_ = p1 - p0;
    s.edge02_ = p2 - p0;
    s.omega_ = triangle_solid_angle(s.to_p0_, s.edge01_, s.edge02_);
    if (!(s.omega_ > 0) || !std::isfinite(s.omega_)) return std::nullopt;
    s.dist_p0_ = length(s.to_p0_);
    s.dir_p0_ = s.to_p0_ / s.dist_p0_;
    const Vec3 b = s.to_p0_ + s.edge01_;
    s.dist_p1_ = length(b);
    s.dir_p1_ = b / s.dist_p1_;
    // Tangent at â toward ĉ: ĉ − (ĉ·â)â ∝ ec − (ec·â)â, formed from the edge.
    const Vec3 t = s.edge02_ - s.dir_p0_ * dot(s.edge02_, s.dir_p0_);
    const double lt = length(t);
    if (!(lt > 0)) return std::nullopt;
    s.tangent_ = t / lt;
    s.edge02_along_tangent_ = lt;
    s.edge02_along_p0_ = dot(s.edge02_, s.dir_p0_);
    s.cos_p0_p1_ = dot(s.to_p0_, b) / (s.dist_p0_ * s.dist_p1_);
    s.dir_p1_dot_tangent_ = dot(s.dir_p1_, s.tangent_);
    s.triple_p0_p1_tangent_ = std::abs(dot(s.to_p0_, cross(s.edge01_, s.tangent_))) / (s.dist_p0_ * s.dist_p1_);
    if (!(s.triple_p0_p1_tangent_ > 0)) return std::nullopt;
    return s;
}

double SphericalTriangle::angle_p0_p2() const {
    if (angle_p0_p2_ < 0)
        angle_p0_p2_ = std::atan2(length(cross(to_p0_, edge02_)), dot(to_p0_, to_p0_ + edge02_));
    return angle_p0_p2_;
}

double SphericalTriangle::sub_solid_angle(double phi) const {
    // VOS on unit vectors â, b̂, p̂(φ) = cos φ â + sin φ t̂, expanded so that nothing cancels.
    const double sp = std::sin(phi), cp = std::cos(phi);
    return 2.0 * std::atan2(triple_p0_p1_tangent_ * sp, (1.0 + cos_p0_p1_) * (1.0 + cp) + dir_p1_dot_tangent_ * sp);
}

DirSample SphericalTriangle::sample(double u1, double u2) const {
    // Invert sub_solid_angle(φ) = u1·Ω in closed form through t = tan(φ/2).
    const double tau = 0.5 * u1 * omega_;
    const double st = std::sin(tau), ct = std::cos(tau);
    double phi = 2.0 * std::atan2((1.0 + cos_p0_p1_) * st, triple_p0_p1_tangent_ * ct - dir_p1_dot_tangent_ * st);
    phi = std::clamp(phi, 0.0, angle_p0_p2());
    const double sp = std::sin(phi), cp = std::cos(phi);
    const Vec3 p = dir_p0_ * cp + tangent_ * sp;
    // The arc b̂ → p̂ is the image of the planar segment p1 → C', C' = p0 + τ (p2 − p0):
    // its plane's normal b × (C' − p1) stays well defined when b̂ and p̂ are nearly
    // antipodal (x just above a large triangle), unlike b̂ × p̂.
    const double tau_c = dist_p0_ * sp / (edge02_along_tangent_ * cp - edge02_along_p0_ * sp);
    const Vec3 m = cross(to_p0_ + edge01_, edge02_ * tau_c - edge01_);
    const Vec3 perp = cross(m, dir_p1_);
    const double lp = length(perp);
    DirSample out;
    if (!(lp > 0) || !std::isfinite(lp)) {
        out.dir = dir_p1_;
    } else {
        // 1 − cos θ' = u2 (1 − cos γ)  ⇔  sin(θ'/2) = √u2 · sin(γ/2), sin(γ/2) = |p̂ − b̂|/2.
        const double half = std::asin(std::min(1.0, std::sqrt(u2) * 0.5 * length(p - dir_p1_)));
        const double th = 2.0 * half;
        out.dir = dir_p1_ * std::cos(th) + perp * (std::sin(th) / lp);
    }
    double b1, b2, t;
    const Vec3 n = cross(edge01_, edge02_);
    const double den = dot(out.dir, n);
    out.dist = den != 0 ? dot(to_p0_, n) / den : std::numeric_limits<double>::max();
    if (!(out.dist > 0) || !std::isfinite(out.dist)) out.dist = hit(out.dir, b1, b2, t) ? t : dist_p0_;
    return out;
}

bool SphericalTriangle::hit(const Vec3& w, double& b1, double& b2, double& t) const {
    const Vec3 n = cross(edge01_, edge02_);
    const double den = dot(w, n);
    if (den == 0) return false;
    t = dot(to_p0_, n) / den;
    if (!(t > 0)) return false;
    const Vec3 r = w * t - to_p0_;
    const double nn = dot(n, n);
    b1 = dot(cross(r, edge02_), n) / nn;
    b2 = dot(cross(edge01_, r), n) / nn;
    return b1 >= -kHitTol && b2 >= -kHitTol && b1 + b2 <= 1 + kHitTol;
}

double SphericalTriangle::pdf(const Vec3& w) const {
    double b1, b2, t;
    return hit(w, b1, b2, t) ? 1.0 / omega_ : 0.0;
}

Point2 SphericalTriangle::invert(const Vec3& w) const {
    double b1 = 0, b2 = 0, t = 0;
    hit(w, b1, b2, t);
    return invert_hit(w, b1, b2);
}

std::optional<Point2> SphericalTriangle::invert_if_hit(const Vec3& w) const {
    double b1 = 0, b2 = 0, t = 0;
    if (!hit(w, b1, b2, t)) return std::nullopt;
    return invert_hit(w, b1, b2);
}

Point2 SphericalTriangle::invert_hit(const Vec3& w, double b1, double b2) const {
    const double s = 1.0 - b1;  // the hit is (1−s)·p1 + s·C', C' = p0 + τ (p2 − p0)
    if (!(s > 0)) return {0.0, 0.0};
    const double tau = std::clamp(b2 / s, 0.0, 1.0);
    const double phi = std::atan2(length(cross(to_p0_, edge02_)) * tau, dot(to_p0_, to_p0_ + edge02_ * tau));
    const double u1 = sub_solid_angle(phi) / omega_;
    const Vec3 p = dir_p0_ * std::cos(phi) + tangent_ * std::sin(phi);
    const Vec3 dw = w - dir_p1_, dp = p - dir_p1_;
    const double dd = dot(dp, dp);
    return {std::clamp(u1, 0.0, 1.0), dd > 0 ? std::clamp(dot(dw, dw) / dd, 0.0, 1.0) : 0.0};
}

}  // namespace omis
