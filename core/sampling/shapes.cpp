#include "sampling/shapes.h"

#include <cmath>
#include <limits>

namespace omis {
namespace {

// A polygon's projected-solid-angle draw and its pdf at a direction that hits
// it, as RectLight and TriangleLight share them (none where nothing projects).
std::optional<LightSample> projected_sample(const std::optional<ProjectedPolygon>& pp,
                                            double u1, double u2) {
    if (!pp) return std::nullopt;
    const DirSample s = pp->sample(u1, u2);
    return LightSample{s.dir, s.dist, pp->pdf_hit(s.dir)};
}

double projected_pdf(const std::optional<ProjectedPolygon>& pp, const Vec3& w) {
    return pp ? pp->pdf_hit(w) : 0.0;
}


constexpr double kTol = 1e-7;  // relative slack of hit tests for samples on an edge

// Ray x + t·w against the plane through x + a spanned by e1, e2: t and the affine
// coordinates (s, v) of the hit in that basis. a is passed (not the plane point) so
// far lights keep their size.
bool hit_plane(const Vec3& a, const Vec3& e1, const Vec3& e2, const Vec3& w, double& t,
               double& s, double& v) {
    const Vec3 n = cross(e1, e2);
    const double den = dot(w, n);
    if (den == 0) return false;
    t = dot(a, n) / den;
    if (!(t > 0) || !std::isfinite(t)) return false;
    const Vec3 r = w * t - a;
    const double nn = dot(n, n);
    s = dot(cross(r, e2), n) / nn;
    v = dot(cross(e1, r), n) / nn;
    return true;
}

std::optional<LightSample> area_sample_record(const Vec3& to_point, const Vec3& unit_normal,
                                              double area) {
    const double d2 = dot(to_point, to_point);
    const double d = std::sqrt(d2);
    if (!(d > 0)) return std::nullopt;
    const Vec3 dir = to_point / d;
    const double cosl = std::abs(dot(dir, unit_normal));
    if (!(cosl > 0)) return std::nullopt;
    return LightSample{dir, d, d2 / (area * cosl)};
}

double area_pdf(const std::optional<ShapeHit>& h, const Vec3& w, const Vec3& unit_normal,
                double area) {
    if (!h) return 0;
    const double cosl = std::abs(dot(w, unit_normal));
    return cosl > 0 ? h->t * h->t / (area * cosl) : 0.0;
}

// A flat light's unit normal and area from one cross product c of its edges
// (area = scale·|c|), as normalize(c) and area() give them.
struct NormalAndArea {
    Vec3 normal;
    double area;
};
NormalAndArea normal_and_area(const Vec3& c, double scale) {
    const double len = length(c);
    return {c / len, scale * len};
}
// The same with the area known: |c| = area / scale exactly (scale 1 or 1/2).
NormalAndArea normal_of_area(const Vec3& c, double scale, double area) {
    return {c / (area / scale), area};
}

// Distance along w to the plane (x + a, normal n), ignoring the light's extent: used
// for directions that a sampler already placed on the light.
double plane_distance(const Vec3& a, const Vec3& n, const Vec3& w) {
    const double den = dot(w, n);
    const double t = den != 0 ? dot(a, n) / den : 0.0;
    return t > 0 && std::isfinite(t) ? t : length(a);
}

}  // namespace

// --------------------------------------------------------------------- rect

double RectLight::area() const { return length(cross(edge_u, edge_v)); }

std::optional<ShapeHit> RectLight::intersect(const Vec3& x, const Vec3& w) const {
    double t, s, v;
    if (!hit_plane(corner - x, edge_u, edge_v, w, t, s, v)) return std::nullopt;
    if (s < -kTol || s > 1 + kTol || v < -kTol || v > 1 + kTol) return std::nullopt;
    return ShapeHit{t, {s, v}};
}

double RectLight::solid_angle(const Vec3& x) const {
    const Vec3 a = corner - x;
    return triangle_solid_angle(a, edge_u, edge_u + edge_v) +
           triangle_solid_angle(a, edge_u + edge_v, edge_v);
}

std::optional<LightSample> RectLight::sample_area(const Vec3& x, double u1, double u2) const {
    const NormalAndArea f = normal_and_area(cross(edge_u, edge_v), 1.0);
    return area_sample_record((corner - x) + edge_u * u1 + edge_v * u2, f.normal, f.area);
}

double RectLight::pdf_area(const Vec3& x, const Vec3& w) const {
    const auto hit = intersect(x, w);
    if (!hit) return 0.0;
    const NormalAndArea f = normal_and_area(cross(edge_u, edge_v), 1.0);
    return area_pdf(hit, w, f.normal, f.area);
}

std::optional<LightSample> RectLight::sample_solid_angle(const Vec3& x, double u1,
                                                         double u2) const {
    const auto sr = SphericalRect::make(x, corner, edge_u, edge_v);
    if (!sr) return std::nullopt;
    return uniform_solid_angle_sample(*sr, u1, u2);
}

double RectLight::pdf_solid_angle(const Vec3& x, const Vec3& w) const {
    const auto sr = SphericalRect::make(x, corner, edge_u, edge_v);
    return sr ? sr->pdf(w) : 0.0;
}

std::optional<LightSample> RectLight::sample_solid_angle(const Vec3& x, const Vec3& n,
                                                         double u1, double u2) const {
    const auto sr = SphericalRect::make(x, corner, edge_u, edge_v);
    if (!sr) return std::nullopt;
    return warped_solid_angle_sample(CosineWarped(*sr, n), u1, u2);
}

double RectLight::pdf_solid_angle(const Vec3& x, const Vec3& n, const Vec3& w) const {
    const auto sr = SphericalRect::make(x, corner, edge_u, edge_v);
    return sr ? CosineWarped(*sr, n).pdf(w) : 0.0;
}

std::optional<ParallelPolygon> RectLight::parallel(const Vec3& x, const Vec3& n) const {
    return ParallelPolygon::make(n, corner - x,
                                 {Vec3{}, edge_u, edge_u + edge_v, edge_v});
}

std::optional<LightSample> RectLight::sample_parallel(const Vec3& x, const Vec3& n, double u1,
                                                      double u2) const {
    const auto pp = parallel(x, n);
    if (!pp) return std::nullopt;
    const Vec3 w = pp->sample(u1, u2);
    return LightSample{w, plane_distance(corner - x, cross(edge_u, edge_v), w), pp->pdf(w)};
}

double RectLight::pdf_parallel(const Vec3& x, const Vec3& n, const Vec3& w) const {
    if (!intersect(x, w)) return 0;
    const auto pp = parallel(x, n);
    return pp ? pp->pdf(w) : 0.0;
}

std::optional<ProjectedPolygon> RectLight::projected(const Vec3& x, const Vec3& n) const {
    return ProjectedPolygon::make(n, corner - x, {Vec3{}, edge_u, edge_u + edge_v, edge_v}, 4);
}

std::optional<LightSample> RectLight::sample_projected(const Vec3& x, const Vec3& n, double u1,
                                                       double u2) const {
    return projected_sample(projected(x, n), u1, u2);
}

double RectLight::pdf_projected(const Vec3& x, const Vec3& n, const Vec3& w) const {
    return intersect(x, w) ? projected_pdf(projected(x, n), w) : 0.0;
}

// ----------------------------------------------------------------- triangle

double TriangleLight::area() const { return 0.5 * length(cross(p1 - p0, p2 - p0)); }

std::optional<ShapeHit> TriangleLight::intersect(const Vec3& x, const Vec3& w) const {
    double t, s, v;
    if (!hit_plane(p0 - x, p1 - p0, p2 - p0, w, t, s, v)) return std::nullopt;
    if (s < -kTol || v < -kTol || s + v > 1 + kTol) return std::nullopt;
    return ShapeHit{t, {s, v}};
}

double TriangleLight::solid_angle(const Vec3& x) const {
    return triangle_solid_angle(p0 - x, p1 - p0, p2 - p0);
}

std::optional<LightSample> TriangleLight::sample_area(const Vec3& x, double u1,
                                                      double u2) const {
    return sample_area(x, u1, u2, area());
}

double TriangleLight::pdf_area(const Vec3& x, const Vec3& w) const {
    return pdf_area(x, w, area());
}

std::optional<LightSample> TriangleLight::sample_area(const Vec3& x, double u1, double u2,
                                                      double area) const {
    const Point2 b = sample_uniform_triangle(u1, u2);
    const NormalAndArea f = normal_of_area(cross(p1 - p0, p2 - p0), 0.5, area);
    return area_sample_record((p0 - x) + (p1 - p0) * b.x + (p2 - p0) * b.y, f.normal, f.area);
}

double TriangleLight::pdf_area(const Vec3& x, const Vec3& w, double area) const {
    return pdf_area_at(intersect(x, w), w, area);
}

double TriangleLight::pdf_area_at(const std::optional<ShapeHit>& hit, const Vec3& w,
                                  double area) const {
    if (!hit) return 0.0;
    const NormalAndArea f = normal_of_area(cross(p1 - p0, p2 - p0), 0.5, area);
    return area_pdf(hit, w, f.normal, f.area);
}

std::optional<LightSample> TriangleLight::sample_solid_angle(const Vec3& x, double u1,
                                                             double u2) const {
    const auto st = SphericalTriangle::make(x, p0, p1, p2);
    if (!st) return std::nullopt;
    return uniform_solid_angle_sample(*st, u1, u2);
}

double TriangleLight::pdf_solid_angle(const Vec3& x, const Vec3& w) const {
    const auto st = SphericalTriangle::make(x, p0, p1, p2);
    return st ? st->pdf(w) : 0.0;
}

std::optional<LightSample> TriangleLight::sample_solid_angle(const Vec3& x, const Vec3& n,
                                                             double u1, double u2) const {
    const auto st = SphericalTriangle::make(x, p0, p1, p2);
    if (!st) return std::nullopt;
    return warped_solid_angle_sample(CosineWarped(*st, n), u1, u2);
}

double TriangleLight::pdf_solid_angle(const Vec3& x, const Vec3& n, const Vec3& w) const {
    const auto st = SphericalTriangle::make(x, p0, p1, p2);
    return st ? CosineWarped(*st, n).pdf(w) : 0.0;
}

std::optional<ParallelPolygon> TriangleLight::parallel(const Vec3& x, const Vec3& n) const {
    return ParallelPolygon::make(n, p0 - x, {Vec3{}, p1 - p0, p2 - p0});
}

std::optional<LightSample> TriangleLight::sample_parallel(const Vec3& x, const Vec3& n,
                                                          double u1, double u2) const {
    const auto pp = parallel(x, n);
    if (!pp) return std::nullopt;
    const Vec3 w = pp->sample(u1, u2);
    return LightSample{w, plane_distance(p0 - x, cross(p1 - p0, p2 - p0), w), pp->pdf(w)};
}

double TriangleLight::pdf_parallel(const Vec3& x, const Vec3& n, const Vec3& w) const {
    if (!intersect(x, w)) return 0;
    const auto pp = parallel(x, n);
    return pp ? pp->pdf(w) : 0.0;
}

std::optional<ProjectedPolygon> TriangleLight::projected(const Vec3& x, const Vec3& n) const {
    return ProjectedPolygon::make(n, p0 - x, {Vec3{}, p1 - p0, p2 - p0, Vec3{}}, 3);
}

std::optional<LightSample> TriangleLight::sample_projected(const Vec3& x, const Vec3& n,
                                                           double u1, double u2) const {
    return projected_sample(projected(x, n), u1, u2);
}

double TriangleLight::pdf_projected(const Vec3& x, const Vec3& n, const Vec3& w) const {
    return intersect(x, w) ? projected_pdf(projected(x, n), w) : 0.0;
}

// ------------------------------------------------------------------ ellipse

double EllipseLight::area() const { return kPi * length(axis_a) * length(axis_b); }

std::optional<ShapeHit> EllipseLight::intersect(const Vec3& x, const Vec3& w) const {
    const Vec3 c = center - x;
    const Vec3 n = cross(axis_a, axis_b);
    const double den = dot(w, n);
    if (den == 0) return std::nullopt;
    const double t = dot(c, n) / den;
    if (!(t > 0) || !std::isfinite(t)) return std::nullopt;
    const Vec3 r = w * t - c;
    const double al = dot(r, axis_a) / dot(axis_a, axis_a);
    const double be = dot(r, axis_b) / dot(axis_b, axis_b);
    if (al * al + be * be > (1 + kTol) * (1 + kTol)) return std::nullopt;
    return ShapeHit{t, {al, be}};
}

std::optional<LightSample> EllipseLight::sample_area(const Vec3& x, double u1, double u2) const {
    const Point2 d = sample_uniform_disk(u1, u2);
    return area_sample_record((center - x) + axis_a * d.x + axis_b * d.y,
                              normalize(cross(axis_a, axis_b)), area());
}

double EllipseLight::pdf_area(const Vec3& x, const Vec3& w) const {
    return area_pdf(intersect(x, w), w, normalize(cross(axis_a, axis_b)), area());
}

std::optional<LightSample> EllipseLight::sample_solid_angle(const Vec3& x, double u1,
                                                            double u2) const {
    const auto se = SphericalEllipse::make(x, center, axis_a, axis_b);
    if (!se) return std::nullopt;
    const DirSample s = se->sample(u1, u2);
    return LightSample{s.dir, s.dist, se->pdf(s.dir)};
}

double EllipseLight::pdf_solid_angle(const Vec3& x, const Vec3& w) const {
    const auto se = SphericalEllipse::make(x, center, axis_a, axis_b);
    return se ? se->pdf(w) : 0.0;
}

std::optional<LightSample> EllipseLight::sample_clipped(const Vec3& x, const ClippedDisk& part,
                                                        double u1, double u2) const {
    const Point2 p = part.sample(u1, u2);
    const double clipped_area = area() * part.area() / kPi;
    return area_sample_record((center - x) + axis_a * p.x + axis_b * p.y,
                              normalize(cross(axis_a, axis_b)), clipped_area);
}

double EllipseLight::pdf_clipped(const Vec3& x, const ClippedDisk& part, const Vec3& w) const {
    const auto h = intersect(x, w);
    if (!h || !part.contains(h->uv)) return 0;
    return area_pdf(h, w, normalize(cross(axis_a, axis_b)), area() * part.area() / kPi);
}

std::optional<ParallelEllipse> EllipseLight::parallel(const Vec3& x, const Vec3& n) const {
    return ParallelEllipse::make(n, center - x, axis_a, axis_b);
}

std::optional<LightSample> EllipseLight::sample_parallel(const Vec3& x, const Vec3& n,
                                                         double u1, double u2) const {
    const auto pe = parallel(x, n);
    if (!pe) return std::nullopt;
    const Vec3 w = pe->sample(u1, u2);
    return LightSample{w, plane_distance(center - x, cross(axis_a, axis_b), w), pe->pdf(w)};
}

double EllipseLight::pdf_parallel(const Vec3& x, const Vec3& n, const Vec3& w) const {
    if (!intersect(x, w)) return 0;
    const auto pe = parallel(x, n);
    return pe ? pe->pdf(w) : 0.0;
}

// ------------------------------------------------------------------- sphere

EllipseLight SphereLight::facing_disk(const Vec3& x) const {
    const Frame f(normalize(center - x));
    return {center, f.s * radius, f.t * radius};
}

std::optional<ShapeHit> SphereLight::intersect(const Vec3& x, const Vec3& w) const {
    return facing_disk(x).intersect(x, w);
}

std::optional<LightSample> SphereLight::sample_area(const Vec3& x, double u1, double u2) const {
    return facing_disk(x).sample_area(x, u1, u2);
}

double SphereLight::pdf_area(const Vec3& x, const Vec3& w) const {
    return facing_disk(x).pdf_area(x, w);
}

std::optional<LightSample> SphereLight::sample_solid_angle(const Vec3& x, double u1,
                                                           double u2) const {
    const Cone c = cone(x);
    if (!(c.one_minus_cos > 0) || !std::isfinite(c.one_minus_cos)) return std::nullopt;
    const Vec3 w = c.sample(u1, u2);
    return LightSample{w, plane_distance(center - x, c.axis, w), 1.0 / c.solid_angle()};
}

double SphereLight::pdf_solid_angle(const Vec3& x, const Vec3& w) const {
    const Cone c = cone(x);
    return c.one_minus_cos > 0 ? c.pdf(w) : 0.0;
}

std::optional<LightSample> SphereLight::sample_parallel(const Vec3& x, const Vec3& n, double u1,
                                                        double u2) const {
    return facing_disk(x).sample_parallel(x, n, u1, u2);
}

double SphereLight::pdf_parallel(const Vec3& x, const Vec3& n, const Vec3& w) const {
    return facing_disk(x).pdf_parallel(x, n, w);
}

// ---------------------------------------------------------------------- sun

std::optional<LightSample> SunLight::sample_solid_angle(double u1, double u2) const {
    const Cone c = cone();
    if (!(c.one_minus_cos > 0)) return std::nullopt;
    return LightSample{c.sample(u1, u2), std::numeric_limits<double>::infinity(),
                       1.0 / c.solid_angle()};
}

double SunLight::pdf_solid_angle(const Vec3& w) const {
    const Cone c = cone();
    return c.one_minus_cos > 0 ? c.pdf(w) : 0.0;
}

}  // namespace omis
