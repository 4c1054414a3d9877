// Projected-solid-angle sampling of a convex planar polygon (rect, triangle): directions
// with density cos θ / Ωp over the part of the polygon above x's horizon, Ωp = ∫ cos θ dω
// (Lambert's formula, SPEC §5). For an unoccluded Lambert receiver under a constant
// emitter the estimate L·cos θ/pdf = L·Ωp is then the same for every draw.
//
// Method (exact, our own; compare Peters 2021): clip the polygon at the horizon plane,
// cut it into a fan of spherical triangles from its first vertex, choose a triangle by
// its Ωp, then work in polar coordinates (s, ψ) about that vertex A, where
// dω = sin s ds dψ and cos θ = (n·A) cos s + (n·u(ψ)) sin s. The azimuth ψ inverts the
// Ωp of the sub-triangle A B C(ψ) (Lambert's formula; its derivative in ψ is the inner
// integral in closed form), then s inverts that inner integral. Both by Newton steps in a
// shrinking bracket. The pdf needs only cos θ and Ωp, so sample() and pdf() agree
// whatever the inversion's rounding.
#pragma once

#include <array>
#include <optional>

#include "math/vec3.h"
#include "sampling/spherical.h"

namespace omis {

class ProjectedPolygon {
public:
    // Polygon x + to_first + offsets[i] (convex, ≤ 4 vertices), receiver normal n (unit).
    // Empty when no part of positive area lies above the horizon.
    static std::optional<ProjectedPolygon> make(const Vec3& n, const Vec3& to_first,
                                                const std::array<Vec3, 4>& offsets,
                                                int count);
    double projected_solid_angle() const { return total_; }
    // A direction toward the polygon and the distance to its plane along it.
    DirSample sample(double u1, double u2) const;
    // Solid angle, for a direction that hits the polygon: max(0, n·w)/Ωp.
    double pdf_hit(const Vec3& w) const { return std::max(0.0, dot(n_, w)) / total_; }

private:
    Vec3 sample_triangle(int i, double u1, double u2) const;
    Vec3 n_, plane_point_, plane_normal_;
    std::array<Vec3, 5> dirs_;  // unit directions of the clipped polygon's vertices
    std::array<double, 3> cdf_{};  // fan triangles (0, i+1, i+2), running Ωp
    int triangles_ = 0;
    double total_ = 0;
};

}  // namespace omis
