// Elementary warps from [0,1)^2. Every routine is a sample / pdf / inverse triple; the
// measure of each pdf is stated. Samplers take the uniforms, never an Rng.
#pragma once

#include "math/vec3.h"

namespace omis {

// A pair of uniforms, or a point in a 2-D parametrisation.
struct Point2 {
    double x = 0, y = 0;
};

// Cosine-weighted hemisphere around local +z: the `bsdf` technique (SPEC §3).
Vec3 sample_cosine_hemisphere(double u1, double u2);
// Solid angle: max(0, cos θ)/π.
double pdf_cosine_hemisphere(const Vec3& w_local);
Point2 invert_cosine_hemisphere(const Vec3& w_local);

// Uniform cone of directions. 1 − cos θmax is stored, not cos θmax, so that cones of
// 1e-8 rad keep their solid angle (1 − cos would round to 0).
struct Cone {
    Vec3 axis;                  // unit
    double one_minus_cos = 0;   // 1 − cos θmax = 2 sin²(θmax/2)

    static Cone from_half_angle(const Vec3& axis, double half_angle);
    // The cone subtended from x by a disk of this radius facing x: a point light of
    // radius r (SPEC §4); half-angle atan(r/d).
    static Cone facing_disk(const Vec3& x, const Vec3& center, double radius);
    // The cone of directions from x that meet a sphere (x outside it): half-angle
    // asin(r/d).
    static Cone around_sphere(const Vec3& x, const Vec3& center, double radius);

    double solid_angle() const { return 2.0 * kPi * one_minus_cos; }
    Vec3 sample(double u1, double u2) const;
    // Solid angle: 1/(2π(1 − cos θmax)) inside, 0 outside.
    double pdf(const Vec3& w) const;
    Point2 invert(const Vec3& w) const;
    // Whether w lies inside (with a relative tolerance for directions produced by sample()).
    bool contains(const Vec3& w) const;
};

// Uniform over a triangle (area measure): returns barycentrics (b1, b2) of the second
// and third vertex; the first has weight 1 − b1 − b2.
Point2 sample_uniform_triangle(double u1, double u2);
Point2 invert_uniform_triangle(const Point2& b);

// Piecewise-bilinear density over [0,1)²: g × g patches through the node weights
// w[j·(g+1) + i] at (i/g, j/g) (all > 0). Drawn by inverting the marginal in y,
// then x given y — both piecewise linear, inverted in closed form per segment
// (g = 1 is pbrt-v4's SampleBilinear) — so the map is monotone in each
// coordinate and keeps a low-discrepancy set's strata.
Point2 sample_piecewise_bilinear(double u1, double u2, const double* w, int g);
// Area density of sample_piecewise_bilinear at p.
double pdf_piecewise_bilinear(const Point2& p, const double* w, int g);

// Uniform over the unit disk (area measure, pdf 1/π), concentric map (Shirley–Chiu).
Point2 sample_uniform_disk(double u1, double u2);
Point2 invert_uniform_disk(const Point2& p);

}  // namespace omis
