// The paper's `parallel` technique (SPEC §3): the light is projected centrally from x
// onto the plane at unit height along n and that planar region is sampled uniformly,
// so p(ω) = 1/(A_proj cos³θ). Defined only when the whole light is above x's horizon
// (the projection of anything touching the horizon is unbounded): make() is empty then.
#pragma once

#include <optional>
#include <vector>

#include "math/vec3.h"
#include "sampling/warp.h"

namespace omis {

// Minimum sine of the elevation of every light point above x's tangent plane.
constexpr double kParallelHorizonEps = 1e-8;

// What every parallel projection has: x's tangent frame and the projected area,
// which alone set the pdf.
class ParallelProjection {
public:
    double projected_area() const { return area_; }
    // Solid angle: 1/(A_proj cos³θ); the caller checks that w hits the light.
    double pdf(const Vec3& w) const;

protected:
    Frame frame_{Vec3{0, 0, 1}};
    double area_ = 0;
};

// Convex triangle or quad. The projected quad is convex and split into two triangles
// chosen in proportion to their projected areas.
class ParallelPolygon : public ParallelProjection {
public:
    // to_first = v0 − x, offsets[i] = v_i − v0 (offsets[0] = 0): far lights keep their size.
    static std::optional<ParallelPolygon> make(const Vec3& n, const Vec3& to_first,
                                               const std::vector<Vec3>& offsets);
    Vec3 sample(double u1, double u2) const;
    Point2 invert(const Vec3& w) const;

private:
    Point2 q0_;
    Point2 dq_[4];  // projected vertex offsets from q0, computed without cancellation
    int count_ = 0;
    double a1_ = 0;
};

// Ellipse center + cos·axis_a + sin·axis_b (perpendicular semi-axes). Its image is an
// ellipse: G·(focal conic r = 1/(1 + ρ·(cos,sin))) + q_center, with ρ the tilt of the
// ellipse's plane — computed in that form, not from a 3×3 conic matrix whose condition
// number squares the distance/size ratio.
class ParallelEllipse : public ParallelProjection {
public:
    // to_center = center − x; axis_a, axis_b the perpendicular semi-axes.
    static std::optional<ParallelEllipse> make(const Vec3& n, const Vec3& to_center,
                                               const Vec3& axis_a, const Vec3& axis_b);
    Vec3 sample(double u1, double u2) const;
    Point2 invert(const Vec3& w) const;

private:
    Point2 qc_, g1_, g2_, rho_dir_, center_z_;
    double az_ = 0, bz_ = 0;
};

}  // namespace omis
