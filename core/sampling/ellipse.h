// Exact samplers for elliptic (disk and ellipse) lights.
//
// SphericalEllipse: the directions from x through a planar ellipse form an elliptic
// cone (a quadric cone: the ellipse is a conic and x its apex). In the cone's own
// frame (axis, e1, e2) the orthographic image of those directions on the plane
// normal to the axis is an ellipse with semi-axes sin α, sin β, α and β being the
// cone's half-angles. The sampler draws the azimuth φ with density
// sin²θb(φ)/(2π sin α sin β), θb(φ) the cone's boundary angle at φ (closed form:
// the polar angle of a uniform point on that orthographic ellipse), then cos θ
// uniform in [cos θb(φ), 1]. Its solid-angle pdf is (1 + cos θb(φ))/(2π sin α sin β):
// exact, constant along each azimuth and within a factor 2 of uniform (1/Ω)
// everywhere, so it behaves like Guillén et al. 2017's area-preserving map without
// their elliptic integrals. The cone's frame and half-angles come from its generator
// [axis_a axis_b center − x] made orthogonal by Lorentz transforms (ellipse.cpp), so
// a light seen edge-on from 1e-9 off its plane keeps its 1e-9-thick cone.
//
// ClippedDisk: uniform (area measure) over the unit disk cut by an axis-aligned
// box, for the part of an ellipse a spread light lets reach x.
#pragma once

#include <optional>

#include "math/vec3.h"
#include "sampling/spherical.h"
#include "sampling/warp.h"

namespace omis {

class SphericalEllipse {
public:
    // The ellipse center + α·axis_a + β·axis_b, α² + β² ≤ 1 (axes perpendicular)
    // seen from x; empty when x lies in its plane.
    static std::optional<SphericalEllipse> make(const Vec3& x, const Vec3& center,
                                                const Vec3& axis_a, const Vec3& axis_b);
    DirSample sample(double u1, double u2) const;
    // Solid angle: (1 + cos θb(φ))/(2π sin α sin β) inside the cone, 0 outside.
    double pdf(const Vec3& w) const;
    Point2 invert(const Vec3& w) const;
    // sin α, sin β: semi-axes of the cone's orthographic image (for tests).
    double sin_a() const { return sa_; }
    double sin_b() const { return sb_; }
    // The cone's axis, about which the pdf is constant along each azimuth (for tests).
    const Vec3& axis() const { return axis_; }

private:
    // The cone's boundary at an azimuth: the orthographic image's rim point (x, y),
    // sin²θb = x² + y² and cos θb.
    struct Rim {
        double x, y, sin2, cos;
    };
    // At the rim parameter ψ (the rim point is (sin α cos ψ, sin β sin ψ)) ...
    Rim rim(double cos_psi, double sin_psi) const;
    // ... and at the azimuth of the local direction (lx, ly).
    Rim rim_toward(double lx, double ly) const;
    Vec3 axis_, e1_, e2_;       // cone frame (world)
    Vec3 to_center_, normal_;   // the light's plane, for the distance along a sample
    double sa_ = 0, sb_ = 0;    // sines of the half-angles
    double ca_ = 0, cb_ = 0;    // and their cosines
    double rim_slack_ = 1;      // (lx/sin α)² + (ly/sin β)² beyond this is outside
};

class ClippedDisk {
public:
    // The unit disk ∩ [a0, a1] × [b0, b1]; empty when the intersection has no area.
    static std::optional<ClippedDisk> make(double a0, double a1, double b0, double b1);
    double area() const { return total_; }
    // A point (α, β) uniform over the region; pdf 1/area() (area measure).
    Point2 sample(double u1, double u2) const;
    Point2 invert(const Point2& p) const;
    bool contains(const Point2& p) const;
    // The region's bounding box.
    Point2 box_min() const { return {lo_, b0_}; }
    Point2 box_max() const { return {hi_, b1_}; }

private:
    double cumulative(double a) const;  // area of the region left of α = a
    double lo_ = 0, hi_ = 0, b0_ = 0, b1_ = 0, base_ = 0, total_ = 0;
};

}  // namespace omis
