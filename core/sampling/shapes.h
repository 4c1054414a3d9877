// Light shapes with every sampler of SPEC §3 as sample / pdf pairs. All pdfs are in
// solid angle (sr⁻¹) as seen from the shading point x; a pdf is 0 for a direction that
// misses the light, so a technique's pdf can be summed over all lights (SPEC §3).
// One-sidedness and radiance are the caller's concern.
#pragma once

#include <optional>

#include "math/vec3.h"
#include "sampling/cosine_warp.h"
#include "sampling/ellipse.h"
#include "sampling/parallel.h"
#include "sampling/projected.h"
#include "sampling/spherical.h"
#include "sampling/warp.h"

namespace omis {

// A direction toward the light, the distance to the light point, and the pdf (sr⁻¹).
struct LightSample {
    Vec3 dir;
    double dist = 0;
    double pdf = 0;
};

// A draw uniform in solid angle from a shape prepared at a point (SphericalRect,
// SphericalTriangle): the one form that lights and per-point caches share.
template <class SphericalShape>
LightSample uniform_solid_angle_sample(const SphericalShape& shape, double u1, double u2) {
    const DirSample s = shape.sample(u1, u2);
    return LightSample{s.dir, s.dist, 1.0 / shape.solid_angle()};
}

// A draw of the `solid-angle` sampler: CosineWarped over the prepared shape.
template <class SphericalShape>
LightSample warped_solid_angle_sample(const CosineWarped<SphericalShape>& warped, double u1,
                                      double u2) {
    double pdf = 0;
    const DirSample s = warped.sample(u1, u2, pdf);
    return LightSample{s.dir, s.dist, pdf};
}

// Ray hit: distance and the shape's own parametrisation of the hit point (used for
// inversion and for binning in tests).
struct ShapeHit {
    double t = 0;
    Point2 uv;
};

// corner + [0,1]·edge_u + [0,1]·edge_v, edges perpendicular; emits toward
// cross(edge_u, edge_v) if one-sided. ShapeHit uv = fractions along the edges.
struct RectLight {
    Vec3 corner, edge_u, edge_v;

    double area() const;
    std::optional<ShapeHit> intersect(const Vec3& x, const Vec3& w) const;
    double solid_angle(const Vec3& x) const;

    // Uniform over the area; pdf d²/(A |cos θ_l|).
    std::optional<LightSample> sample_area(const Vec3& x, double u1, double u2) const;
    double pdf_area(const Vec3& x, const Vec3& w) const;
    // Uniform over the solid angle (SphericalRect); pdf 1/Ω.
    std::optional<LightSample> sample_solid_angle(const Vec3& x, double u1, double u2) const;
    double pdf_solid_angle(const Vec3& x, const Vec3& w) const;
    // The `solid-angle` sampler at a receiver of normal n: the same, bent toward
    // cos θ (CosineWarped).
    std::optional<LightSample> sample_solid_angle(const Vec3& x, const Vec3& n, double u1,
                                                  double u2) const;
    double pdf_solid_angle(const Vec3& x, const Vec3& n, const Vec3& w) const;
    // Parallel projection; empty / 0 when the light is not wholly above the horizon.
    std::optional<ParallelPolygon> parallel(const Vec3& x, const Vec3& n) const;
    std::optional<LightSample> sample_parallel(const Vec3& x, const Vec3& n, double u1,
                                               double u2) const;
    double pdf_parallel(const Vec3& x, const Vec3& n, const Vec3& w) const;
    // ∝ cos θ over the part above the horizon (ProjectedPolygon); pdf cos θ/Ωp.
    std::optional<ProjectedPolygon> projected(const Vec3& x, const Vec3& n) const;
    std::optional<LightSample> sample_projected(const Vec3& x, const Vec3& n, double u1,
                                                double u2) const;
    double pdf_projected(const Vec3& x, const Vec3& n, const Vec3& w) const;
};

// Triangle p0 p1 p2; emits toward cross(p1 − p0, p2 − p0) if one-sided.
// ShapeHit uv = barycentrics of p1 and p2.
struct TriangleLight {
    Vec3 p0, p1, p2;

    double area() const;
    std::optional<ShapeHit> intersect(const Vec3& x, const Vec3& w) const;
    double solid_angle(const Vec3& x) const;

    std::optional<LightSample> sample_area(const Vec3& x, double u1, double u2) const;
    double pdf_area(const Vec3& x, const Vec3& w) const;
    // The same with area() given (kept by its owner: Light::triangle_area),
    // bit for bit, without its square root.
    std::optional<LightSample> sample_area(const Vec3& x, double u1, double u2,
                                           double area) const;
    double pdf_area(const Vec3& x, const Vec3& w, double area) const;
    // The same from intersect(x, w)'s result, where the caller made it.
    double pdf_area_at(const std::optional<ShapeHit>& hit, const Vec3& w, double area) const;
    std::optional<LightSample> sample_solid_angle(const Vec3& x, double u1, double u2) const;
    double pdf_solid_angle(const Vec3& x, const Vec3& w) const;
    std::optional<LightSample> sample_solid_angle(const Vec3& x, const Vec3& n, double u1,
                                                  double u2) const;
    double pdf_solid_angle(const Vec3& x, const Vec3& n, const Vec3& w) const;
    std::optional<ParallelPolygon> parallel(const Vec3& x, const Vec3& n) const;
    std::optional<LightSample> sample_parallel(const Vec3& x, const Vec3& n, double u1,
                                               double u2) const;
    double pdf_parallel(const Vec3& x, const Vec3& n, const Vec3& w) const;
    std::optional<ProjectedPolygon> projected(const Vec3& x, const Vec3& n) const;
    std::optional<LightSample> sample_projected(const Vec3& x, const Vec3& n, double u1,
                                                double u2) const;
    double pdf_projected(const Vec3& x, const Vec3& n, const Vec3& w) const;
};

// Disk or ellipse center + α·axis_a + β·axis_b, α² + β² ≤ 1, semi-axes perpendicular
// (Blender DISK/ELLIPSE). Emits toward cross(axis_a, axis_b). ShapeHit uv = (α, β).
struct EllipseLight {
    Vec3 center, axis_a, axis_b;

    double area() const;
    std::optional<ShapeHit> intersect(const Vec3& x, const Vec3& w) const;

    std::optional<LightSample> sample_area(const Vec3& x, double u1, double u2) const;
    double pdf_area(const Vec3& x, const Vec3& w) const;
    // The elliptic cone seen from x (SphericalEllipse): exact, within 2× of uniform.
    std::optional<LightSample> sample_solid_angle(const Vec3& x, double u1, double u2) const;
    double pdf_solid_angle(const Vec3& x, const Vec3& w) const;
    // Uniform over the part of the ellipse whose (α, β) lie in `part` (area measure;
    // pdf d²/(A·part.area()/π·|cos θ_l|) in solid angle), 0 elsewhere.
    std::optional<LightSample> sample_clipped(const Vec3& x, const ClippedDisk& part,
                                              double u1, double u2) const;
    double pdf_clipped(const Vec3& x, const ClippedDisk& part, const Vec3& w) const;
    std::optional<ParallelEllipse> parallel(const Vec3& x, const Vec3& n) const;
    std::optional<LightSample> sample_parallel(const Vec3& x, const Vec3& n, double u1,
                                               double u2) const;
    double pdf_parallel(const Vec3& x, const Vec3& n, const Vec3& w) const;
};

// Point light of radius r > 0: a disk of radius r centred on the light and facing x
// (SPEC §4). Its solid angle is exactly a cone, so solid-angle sampling is exact.
struct SphereLight {
    Vec3 center;
    double radius = 0;

    // The disk as seen from x (depends on x).
    EllipseLight facing_disk(const Vec3& x) const;
    Cone cone(const Vec3& x) const { return Cone::facing_disk(x, center, radius); }
    std::optional<ShapeHit> intersect(const Vec3& x, const Vec3& w) const;

    std::optional<LightSample> sample_area(const Vec3& x, double u1, double u2) const;
    double pdf_area(const Vec3& x, const Vec3& w) const;
    std::optional<LightSample> sample_solid_angle(const Vec3& x, double u1, double u2) const;
    double pdf_solid_angle(const Vec3& x, const Vec3& w) const;
    std::optional<LightSample> sample_parallel(const Vec3& x, const Vec3& n, double u1,
                                               double u2) const;
    double pdf_parallel(const Vec3& x, const Vec3& n, const Vec3& w) const;
};

// Sun with an angular radius (half of Blender's `angle`, which is a diameter):
// a cone of directions at infinite distance (dist = +inf in the samples).
struct SunLight {
    Vec3 to_sun;  // unit
    double half_angle = 0;

    Cone cone() const { return Cone::from_half_angle(to_sun, half_angle); }
    std::optional<LightSample> sample_solid_angle(double u1, double u2) const;
    double pdf_solid_angle(const Vec3& w) const;
};

}  // namespace omis
