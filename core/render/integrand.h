// The integrand of direct lighting along a direction from a shading
// position: the radiance of the lights seen there times the receiver's
// closure, split into the part BSDF rays see and the hidden part; one
// occlusion rule for every shadow test; a world seen through emitters split
// from them; and the delta lights, summed outside MIS. Internal to the
// lighting core (render/*.cpp).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "render/lights_along.h"

namespace omis {

// An emissive triangle is geometry too: a closest hit within this relative
// depth of it is the emitter itself or a coplanar neighbour, not a blocker.
constexpr double kEmitterDepthTolerance = 1e-4;

// The emitter-depth occlusion rule, for every shadow test: how far from the
// ray's (offset) origin a surface hides `light`'s emitting point `depth`
// away — short of a triangle's depth by the tolerance, so that its own
// surface or a coplanar neighbour does not shadow it.
inline double shadow_depth(const Light& light, double depth) {
    return light.type == LightType::Triangle ? depth * (1 - kEmitterDepthTolerance) : depth;
}
// Whether the closest hit `blocker` hides `light`'s emitting point `depth`
// from the origin (a triangle is not hidden by itself).
inline bool hides(const RayHit& blocker, const Light& light, double depth) {
    if (light.type == LightType::Triangle && blocker.mesh == light.mesh &&
        blocker.triangle == light.mesh_triangle)
        return false;
    return !(blocker.t >= shadow_depth(light, depth));
}

class Integrand {
public:
    struct Value {
        // Lights BSDF rays see, and those they do not (or, world_through():
        // the emitters' part and the world's, seen through emitters).
        Vec3 main, hidden;
    };
    Integrand(const LightingContext& context, LightsAlong& along, LightingCounters& counters);

    // The integrand along w from x (shading normal n, geometric ng).
    Value at(const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& w);
    // at() where every light casts shadows (clips_at_blocker()), from the
    // closest hit first: of a direction a light technique drew toward light
    // `sampled_light` (at sampled_distance from x), or with sampled_light =
    // ~0u of a BSDF direction. Where the blocker hides the sampled light (or,
    // for a BSDF direction, where there is one), only the lights up to it are
    // listed, which are all that can be seen; where nothing is hit and every
    // shaped light is an emissive triangle of the geometry
    // (shapes_in_geometry_), only the unshaped lights (and the sampled one).
    // The same value as at(), but on the edges of light shapes (a set of
    // directions of measure zero).
    Value to_blocker(const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& w,
                     std::uint32_t sampled_light, double sampled_distance);
    // Light l's own part of the integrand along w (visible from x or not).
    Value of_light(std::uint32_t l, const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& w);
    // of_light before its shadow ray: light l's radiance toward x along w,
    // the receiver's cosine factor and the emitting point's distance; none
    // where w is below x's horizon or l sends nothing along it.
    struct Unoccluded {
        Vec3 radiance;
        double cosine_factor, distance;
    };
    std::optional<Unoccluded> unoccluded(std::uint32_t l, const Vec3& x, const Vec3& n,
                                         const Vec3& w) const;
    // Whether a shadow ray from x along w meets something before light l's
    // emitting point `distance` away (false where no shadow rays are traced);
    // for a mesh light, whether the closest hit is off its mesh.
    bool occluded(std::uint32_t l, const Vec3& x, const Vec3& ng, const Vec3& w, double distance);
    // world_through(): moves the world's part of f (a direction whose first
    // hit, `blocker`, if any, emits) from main to hidden, where main holds it
    // already (nothing hit) or holds the emitter's L_e (L_e − L_w). Without
    // such a world the blocker's mesh is not looked up (~30 instructions a
    // sample among emissive triangles).
    void split_world(Value& f, const Vec3& x, const Vec3& w,
                     const std::optional<RayHit>& blocker) const {
        if (world_through_ == ~0u) return;
        if (blocker && !context_.scene.geometry().mesh(blocker->mesh).is_emissive()) return;
        const auto e = emitted_radiance(context_.scene.lights()[world_through_], x, w);
        if (!e) return;
        f.main -= e->radiance;
        f.hidden += e->radiance;
    }
    // The delta lights' E/π at p (outside MIS); u places the draws where
    // they are drawn (EffectPlan::sample_delta_lights).
    Vec3 delta_lighting(const SurfacePoint& p, double u);

    // Whether light samples take to_blocker (set from the scene). Among
    // emissive triangles: with analytic lights alone, at() often needs only
    // an occlusion ray, cheaper than a closest hit.
    bool clips_at_blocker() const { return clip_at_blocker_; }
    // Whether BSDF directions take to_blocker too: where a world lies along
    // every one of them, at() traces a ray for each anyway, after an all-hits
    // query of the emitter shapes that the closest hit makes unneeded where it
    // meets a surface that does not emit or, with shapes_in_geometry_, nothing.
    bool bsdf_to_blocker() const { return bsdf_to_blocker_; }
    // The world light when the plan sees it through emitters, else ~0u.
    std::uint32_t world_through() const { return world_through_; }

private:
    // The radiance of the mesh lights among `lights` whose mesh is the
    // closest hit along w (`blocker`), added to f (before the closure).
    void add_mesh_lights_seen(Value& f, const std::vector<std::uint32_t>& lights,
                              const std::optional<RayHit>& blocker) const;
    // f times the receiver's closure (Lambert: cosθ/π), as Cycles' Diffuse
    // bake sees it.
    void scale_by_closure(Value& f, double cos_theta) const;
    const std::vector<std::uint32_t>& lights_to_blocker(const Vec3& x, const Vec3& w,
                                                        const std::optional<RayHit>& blocker,
                                                        bool complete, double offset,
                                                        std::uint32_t sampled_light,
                                                        double sampled_distance);
    // GeometryScene::ListedLight: light l's record and its tree pmf's.
    static void prefetch_listed(void* self, std::uint32_t l);

    const LightingContext& context_;
    LightsAlong& along_;
    LightingCounters& counters_;
    struct Hit {
        std::uint32_t light;
        Emitted emitted;
    };
    std::vector<Hit> hits_;               // at()'s lights seen
    std::vector<std::uint32_t> clipped_;  // to_blocker's lights
    std::vector<std::uint32_t> merged_;   // ... from the closest hit's traversal
    LightSelector::Memo delta_memo_;      // the delta tree's branching at the point
    const bool clip_at_blocker_;
    const std::uint32_t world_light_;  // the scene's (first) world light, else ~0u
    const bool bsdf_to_blocker_;
    const std::uint32_t world_through_;
    // Every light with an emitter shape is an emissive triangle, which the
    // geometry holds: a ray that meets no surface crosses no such shape.
    const bool shapes_in_geometry_;
};

}  // namespace omis
