// Lights with the semantics of Blender 3.4 / Cycles (SPEC §3–§4), stored in
// physical units, and everything the direct-lighting engine asks of them:
// emitted radiance along a direction, per-sampler sample/pdf pairs, power and
// unoccluded irradiance for light selection, and delta-light irradiance.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "math/vec3.h"
#include "sampling/shapes.h"

namespace omis {

class EnvironmentMap;  // lights/environment_map.h: an image-based world

// Mesh: an emissive mesh drawn as one light (Scene::commit groups compact
// meshes): directions toward its bounding sphere, its radiance where the
// first hit along them is on the mesh.
enum class LightType { Rect, Ellipse, Triangle, Point, Spot, Sun, World, Mesh };
constexpr int kLightTypes = 8;  // how many LightType values
const char* light_type_name(LightType type);

// How a light technique draws a direction toward the light it has chosen — the
// light's shape (SPEC §3); choosing the light is SelectionRule's part.
// ProjectedSolidAngle draws ∝ cos θ on rects and triangles; other shapes use their
// solid-angle sampler under that name.
enum class ShapeSampler { Area, SolidAngle, Parallel, ProjectedSolidAngle };
const char* shape_sampler_name(ShapeSampler sampler);

// The fields every integrated light reads per sample come first, then the
// triangle's: an emissive triangle (the many-light case) is read from the
// first two cache lines of its record instead of five of six (among 100k
// lights each is a miss).
struct alignas(64) Light {
    LightType type = LightType::Rect;
    bool two_sided = false;  // Rect/Ellipse/Triangle; emissive meshes are two-sided
    bool cast_shadow = true;      // Blender: cycles.cast_shadow
    bool visible_to_bsdf = true;  // Blender: cycles.use_multiple_importance_sampling
    std::uint32_t mesh = ~0u, mesh_triangle = ~0u;  // Triangle: where it is in the geometry
    // Rect/Ellipse/Triangle/World: radiance, W/(m² sr). Point/Spot: intensity,
    // W/sr. Sun: irradiance on a surface facing it, W/m². RGB.
    Vec3 emission;
    double spread = kPi;     // Rect/Ellipse: Blender's spread angle
    TriangleLight triangle;  // Triangle (emissive mesh triangle)
    // Triangle: triangle.area(), made once: a sample's tiny-light test, area
    // draw and density and the emitted radiance's normal took its cross
    // product's length (a square root) at every call.
    double triangle_area = 0;

    RectLight rect;          // Rect
    EllipseLight ellipse;    // Ellipse (disk when the semi-axes are equal)
    // Rect/Ellipse with spread < π: the spread's constants, set by the
    // factories with the shape, so that the per-point reach test and the
    // per-sample falloff compute no tangent, normal or length (light.cpp).
    struct SpreadConstants {
        double tan_half = 0;                       // tan(spread/2)
        double cot_half = 0, one_minus_b_cot_b = 1;  // the falloff's (b = spread/2)
        Vec3 unit_normal;                          // of the light's plane
        double length1 = 0, length2 = 0;           // of its two spanning vectors
    } spread_constants;

    Vec3 position;           // Point/Spot; Mesh: its bounding sphere's centre
    double radius = 0;       // Point/Spot: > 0 makes a disk facing the receiver; Mesh: the sphere's
    double mesh_area = 0;    // Mesh: the area of its triangles (one side)
    Vec3 spot_axis;          // Spot: unit direction the spot shines along
    double spot_cos_half = -1, spot_smooth = 0;  // Spot: cos(size/2), blend width in cos

    Vec3 to_sun;             // Sun: unit direction toward the sun
    double sun_half_angle = 0;

    // World: an image-based world (environment_map.h), else the constant
    // `emission`; with a map, `emission` holds its mean radiance.
    std::shared_ptr<const EnvironmentMap> environment;

    // Lights integrated by one deterministic shadow ray, outside MIS.
    bool is_delta() const;
    // Emitted flux used by `power` selection (luminance, W); distant lights
    // (sun, world) are measured over a disk of the scene's bounding radius.
    double power(double scene_radius) const;
};

// Starts reading the first two cache lines of a light's record, all that an
// emissive triangle's sample reads (among 100k lights each is a cache miss);
// reads nothing itself, so the pointer may be any address.
inline void prefetch_record(const Light* light) {
    const char* record = reinterpret_cast<const char*>(light);
    __builtin_prefetch(record);
    __builtin_prefetch(record + 64);
}

// Factories validate and throw std::invalid_argument naming the problem
// (zero area, NaN, negative emission, non-perpendicular edges, ...).
Light make_rect_light(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                      const Vec3& radiance, bool two_sided, double spread);
Light make_ellipse_light(const Vec3& center, const Vec3& axis_a, const Vec3& axis_b,
                         const Vec3& radiance, bool two_sided, double spread);
Light make_triangle_light(const Vec3& p0, const Vec3& p1, const Vec3& p2,
                          const Vec3& radiance, bool two_sided);
Light make_point_light(const Vec3& position, const Vec3& intensity, double radius);
// spot_size: full cone angle (Blender), spot_blend in [0, 1].
Light make_spot_light(const Vec3& position, const Vec3& direction, const Vec3& intensity,
                      double radius, double spot_size, double spot_blend);
// direction: the way the light travels (Blender's −Z); angle: full angular diameter.
Light make_sun_light(const Vec3& direction, const Vec3& irradiance, double angle);
Light make_world_light(const Vec3& radiance);
// An emissive mesh as one two-sided light: `mesh` (its id in the geometry),
// the centre and radius of a sphere holding it, its area and radiance.
Light make_mesh_light(std::uint32_t mesh, const Vec3& centre, double radius, double area,
                      const Vec3& radiance);
// Whether a mesh light draws its bounding sphere's cone at x (x outside the
// sphere), or else the cosine hemisphere about n.
bool mesh_light_draws_cone(const Light& light, const Vec3& x);
// Whether w from x may meet a mesh light's mesh: it meets the bounding
// sphere (the whole of its cone, not the disk facing x that a point light's
// radius makes), or x is inside it (or within the cone's margin).
bool mesh_light_along(const Light& light, const Vec3& x, const Vec3& w);

// Rec. 709 luminance, the scalar used for selection weights and noise.
inline double luminance(const Vec3& rgb) {
    return 0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z;
}

// Radiance arriving at x from direction w (unit) if w hits the light, with the
// distance to the emitting point (+inf for sun and world). Not for delta lights.
struct Emitted {
    Vec3 radiance;
    double distance = 0;
};
// Mesh lights emit through their mesh's triangles: the first hit along w
// decides (render/integrand.cpp); here they give none.
std::optional<Emitted> emitted_radiance(const Light& light, const Vec3& x, const Vec3& w);
// The same for a triangle light whose shape w meets at `distance` (its
// intersect's t): a caller that first tests the hit (against a blocker) forms
// the radiance of the triangles it keeps only.
Emitted triangle_emitted(const Light& light, const Vec3& w, double distance);

// Irradiance at (x, n) from a delta light (cosine included), with the unit
// direction and distance for its shadow ray; empty when it cannot reach x.
struct DeltaIllumination {
    Vec3 irradiance;
    Vec3 direction;
    double distance = 0;
};
std::optional<DeltaIllumination> delta_illumination(const Light& light, const Vec3& x,
                                                    const Vec3& n);

// Can this light add anything at (x, n)? False when it lies wholly below the
// horizon or x is behind a one-sided emitter: such lights are left out of
// every light technique's selection at x (the per-point effect plan).
bool light_reaches(const Light& light, const Vec3& x, const Vec3& n);

// Whether `sampler` can draw directions toward this light at (x, n): the
// parallel projection needs the light wholly above the horizon and a planar
// or disk shape. Sun and world have no shape of their own: they use their
// cone and the cosine hemisphere for every sampler (see sample_light).
bool sampler_applies(const Light& light, ShapeSampler sampler, const Vec3& x, const Vec3& n);

// The rectangle a rect light's samplers draw from at x: the whole light, or with
// spread < π the part of it inside the bounding square of the spread's reach
// (Cycles 3.4); empty when no point of the light can reach x.
std::optional<RectLight> rect_reaching(const Light& light, const Vec3& x);

// Whether a spread (if any) lets every point of an ellipse light reach x: its
// solid-angle sampler then draws the whole elliptic cone (SphericalEllipse),
// else the clipped part by area.
bool ellipse_wholly_reaches(const Light& light, const Vec3& x);

// Whether the ray x + t·w (t > 0) crosses the shape of a rect, ellipse or
// triangle light, with the hit tests' slack (true for other types): a cheap
// test before a density that needs the shape prepared at x.
bool ray_crosses_light(const Light& light, const Vec3& x, const Vec3& w);

// A direction toward the light drawn by `sampler`, with its solid-angle pdf
// (sr⁻¹), and the matching pdf evaluation (0 where w misses the light).
std::optional<LightSample> sample_light(const Light& light, ShapeSampler sampler,
                                        const Vec3& x, const Vec3& n, double u1, double u2);
double light_pdf(const Light& light, ShapeSampler sampler, const Vec3& x, const Vec3& n,
                 const Vec3& w);

// Unoccluded irradiance luminance at (x, n) (SPEC §5 for polygons): the
// weight of `unoccluded` selection, the paper's "trained" technique. For rects
// and ellipses with spread, the spread-weighted irradiance within 1 %.
double unoccluded_irradiance(const Light& light, const Vec3& x, const Vec3& n);

}  // namespace omis
