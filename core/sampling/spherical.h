// Uniform sampling of the solid angle subtended by planar rectangles (Ureña, Fajardo
// & King 2013) and triangles (Arvo 1995), rewritten so that every step keeps relative
// precision for lights of 1e-12 sr, lights covering nearly a hemisphere and shading
// points 1e-9 above the light's plane. The pdf is 1/Ω over the whole support in every
// configuration, so sample() and pdf() never disagree.
#pragma once

#include <optional>
#include <vector>

#include "math/vec3.h"
#include "sampling/warp.h"

namespace omis {

// Solid angle of the triangle (a, a+e1, a+e2) seen from the origin (Van Oosterom &
// Strackee, atan2 form). Edges are passed, not vertices, because far lights lose
// their size in the subtraction of two long vectors.
double triangle_solid_angle(const Vec3& a, const Vec3& e1, const Vec3& e2);
// Convex polygon given by an offset from x and vertex offsets from that point.
double polygon_solid_angle(const Vec3& to_first, const std::vector<Vec3>& offsets);

// A direction and the distance to the light point along it.
struct DirSample {
    Vec3 dir;
    double dist = 0;
};

// The rectangle corner + [0,1]·edge_u + [0,1]·edge_v (edges perpendicular) seen from x.
// Ureña's parametrisation: azimuth φ about edge_v chosen so that the part of the
// rectangle left of it has solid angle u1·Ω, then h = cos(angle to edge_v) uniform.
// The closed-form inversion of the paper loses all digits for tiny or near-plane
// rectangles; here the first coordinate is found by safeguarded Newton on a stable
// solid-angle function whose derivative is exact (dΩ/dφ = h1 − h0), from a
// cubic Hermite guess through that derivative at both edges.
class SphericalRect {
public:
    // Empty when x lies in the rectangle's plane or the edges are not perpendicular.
    static std::optional<SphericalRect> make(const Vec3& x, const Vec3& corner,
                                             const Vec3& edge_u, const Vec3& edge_v);
    double solid_angle() const { return omega_; }
    DirSample sample(double u1, double u2) const;
    // sample(i, j).dir for i, j ∈ {0, 1}: the unit direction to the corner
    // corner + i·edge_u + j·edge_v, in closed form.
    Vec3 corner_direction(int i, int j) const;
    // Solid angle: 1/Ω if w hits the rectangle, else 0.
    double pdf(const Vec3& w) const;
    Point2 invert(const Vec3& w) const;

private:
    // Ω of [x0, x0+w] × [y0, y1]; bc_lengths as half_angle_vector's.
    double sub_solid_angle(double w, double* bc_lengths = nullptr) const;
    // dΩ/dφ = h1 − h0 at the edge whose corners at y0 and y1 lie at distances
    // len0 and len1 (h = cos of the angle to ey: y/len). Exact.
    double dsolid_angle_dphi(double len0, double len1) const { return y1_ / len1 - y0_ / len0; }
    // Ω/2 of [x0, x0+w] × [y0, y1] as the angle of (cos, sin) ∝ (x, y), y ≥ 0.
    // bc_lengths (if asked): |b|, |c| of the far corners (x0 + w, y0), (x0 + w, y1).
    void half_angle_vector(double w, double& x, double& y, double* bc_lengths = nullptr) const;
    // Newton's first δ for u1 (the Hermite cubic of make()'s end slopes).
    double first_guess(double u1) const;
    // x(φ0+δ) − x0, from sin δ and cos_phi = cos(φ0+δ).
    double width_at(double delta, double sin_delta, double cos_phi) const;
    // sin δ, cos(φ0+δ) and sin(φ0+δ) from one sincos of δ: φ0 itself (an
    // atan2 per shape) is never formed.
    void rotate(double delta, double& sin_delta, double& cos_phi, double& sin_phi) const;
    void turn(double cos_delta, double sin_delta, double& cos_phi, double& sin_phi) const;
    double h_at(double cos_phi, double y) const;
    Vec3 ex_, ey_, ez_;  // ez points from the plane toward x
    double x0_ = 0, y0_ = 0, y1_ = 0, W_ = 0, H_ = 0, z_ = 0;  // z_ = distance to plane
    double cos_phi0_ = 1, sin_phi0_ = 0, dphi_ = 0, r0_ = 0, omega_ = 0;
    double la_ = 0, ld_ = 0, ad_ = 0;  // |a|, |d|, a·d of sub_solid_angle's fixed corners
    double far_lengths_[2] = {0, 0};  // |b|, |c| at w = W: the corners at x0 + W
    double guess_slope0_ = 1, guess_slope1_ = 1;  // dδ/du1 / dphi at u1 = 0, 1 (capped)
};

// The triangle (p0, p1, p2) seen from x: Arvo's two steps (sub-triangle p0 p1 C' of
// solid angle u1·Ω with C' on arc p0 p2, then 1 − cos of the angle from p1 uniform on
// the arc p1 C'), with the first step solved in a closed form that needs no
// subtraction of nearly equal angles.
class SphericalTriangle {
public:
    // Empty when the triangle is degenerate or x lies in its plane.
    static std::optional<SphericalTriangle> make(const Vec3& x, const Vec3& p0,
                                                 const Vec3& p1, const Vec3& p2);
    double solid_angle() const { return omega_; }
    DirSample sample(double u1, double u2) const;
    // sample(i, j).dir for i, j ∈ {0, 1}, in closed form: p̂1 where j = 0
    // (the second step starts at p1), p̂0 at (0, 1), p̂2 at (1, 1). Inline:
    // the cosine warp asks for all four at every shape it prepares.
    Vec3 corner_direction(int i, int j) const {
        if (j == 0) return dir_p1_;
        return i == 0 ? dir_p0_ : normalize(to_p0_ + edge02_);
    }
    // Solid angle: 1/Ω if w hits the triangle, else 0.
    double pdf(const Vec3& w) const;
    Point2 invert(const Vec3& w) const;
    // invert(w) where w hits the triangle (pdf(w) > 0), else empty: the two
    // from one hit test (a density's, ~10 % of a light's density at x).
    std::optional<Point2> invert_if_hit(const Vec3& w) const;

private:
    double sub_solid_angle(double phi) const;
    // invert(w) from w's hit (barycentrics b1, b2).
    Point2 invert_hit(const Vec3& w, double b1, double b2) const;
    // The arc from p̂0 to p̂2, which only sample() needs: formed at its first
    // call (an atan2), not by make() for a shape asked only its density.
    double angle_p0_p2() const;
    // Barycentrics (of p1, p2) and distance of the hit of w, if any.
    bool hit(const Vec3& w, double& b1, double& b2, double& t) const;
    // Vectors from x (to_p0_ = p0 − x) and the edges from p0, kept apart so far
    // lights keep their size; unit directions to p0 and p1; the unit tangent at
    // p̂0 of the great circle toward p̂2.
    Vec3 to_p0_, edge01_, edge02_, dir_p0_, dir_p1_, tangent_;
    double dist_p0_ = 0, dist_p1_ = 0;           // |p0 − x|, |p1 − x|
    double edge02_along_tangent_ = 0;            // (p2 − p0)·t̂, the length of its tangential part
    double edge02_along_p0_ = 0;                 // (p2 − p0)·p̂0
    double cos_p0_p1_ = 0;                       // p̂0·p̂1
    double dir_p1_dot_tangent_ = 0;              // p̂1·t̂
    double triple_p0_p1_tangent_ = 0;            // |p̂0·(p̂1 × t̂)|
    mutable double angle_p0_p2_ = -1;            // angle_p0_p2(), once formed (≥ 0)
    double omega_ = 0;                           // solid angle
};

}  // namespace omis
