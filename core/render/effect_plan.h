// The effect plan (SPEC §3): what a scene calls for, decided once per scene and
// refined per shading point, so that effects the scene does not use cost
// nothing — no rays, no pdf evaluations, no MIS system entries.
#pragma once

#include <string>
#include <vector>

#include "render/scene.h"
#include "render/techniques.h"

namespace omis {

struct EffectPlan {
    // What the scene holds.
    int lights_by_type[kLightTypes] = {};  // indexed by LightType
    int integrated_lights = 0;   // non-delta lights: the MIS system's business
    int delta_lights = 0;        // one shadow ray each, outside MIS
    // Some geometry could occlude a light from a point shaded (not where the
    // points lie on a flat mesh in whose plane every mesh lies).
    bool shadow_rays = false;
    bool bsdf_invisible_lights = false;  // lights only light techniques may see
    // The (constant) world is left to the `bsdf` technique, as Cycles leaves a
    // constant world to its BSDF rays: light techniques then draw only the
    // local emitters. When the world is a minor light (kMinorWorldPower).
    bool world_by_bsdf = false;
    // The world left to `bsdf` is seen through emissive triangles (issue 9):
    // the integrand along ω is split into the world's part, L_w wherever no
    // surface that does not emit is hit first (estimated by `bsdf` alone), and
    // the emitters' part, L_e − L_w on an emitter hit first (by MIS over all
    // techniques). Their sum is the old integrand at every ω: unbiased. The
    // world's cosine draws then see Bernoulli noise only from the surfaces
    // that do not emit, and the light technique integrates the emitters'
    // occlusion of the world. See world_seen_through_emitters (effect_plan.cpp).
    bool world_through_emitters = false;
    // The world seen through emitters, around few surfaces that do not emit
    // (world_occluders, effect_plan.cpp): the world's part is
    // L_w·(1 − B), B the share of the cosine-weighted hemisphere whose first
    // hit is such a surface, and `bsdf`'s draws estimate B by directions drawn
    // toward the occluders' bounding boxes instead of over the hemisphere.
    // One box per mesh that does not emit (world space, axis-aligned).
    struct OccluderBox {
        std::uint32_t mesh = 0;
        Vec3 lo, hi;
    };
    std::vector<OccluderBox> world_occluders;
    // Many delta lights: their sum is estimated by drawing delta_samples of
    // them per round from a light tree instead of one shadow ray each.
    bool sample_delta_lights = false;
    int delta_samples = 0;

    // The requested techniques and whether the scene lets each apply at all.
    std::vector<Technique> techniques;
    std::vector<int> samples;     // per round
    std::vector<bool> enabled;    // scene-level verdict
    std::vector<std::string> why; // one reason per technique
    bool mis_system = false;      // any enabled technique: a per-point system is built

    std::string to_string() const;
};

// points_mesh: the mesh every point shaded lies on (a bake's), when known;
// past the meshes (the default), points anywhere.
EffectPlan plan_effects(const Scene& scene, const std::vector<Technique>& techniques,
                        const std::vector<int>& samples, std::uint32_t points_mesh = ~0u);

// The effect plan's default choice of techniques and samples per round for a
// scene (what a bake uses when the caller names none), all with solid-angle
// shape sampling: one technique for one light; for several (≤ 16), uniform
// selection when they are local and of comparable power, else defensive
// selection; the tree alone for many; plus bsdf for a world among many lights,
// for a huge light (an emissive mesh as large as the scene counts as one), and
// for a minor world among few lights (left to bsdf; the light technique then
// selects among the others).
// Beyond these counts the plan stops looping over lights per point: delta
// lights are drawn from a light tree, and the default light technique selects
// by the tree instead of by exact unoccluded irradiance. Integrated lights:
// bench_emitters shows 16 lights with `unoccluded` costing about what 256 cost
// with the tree, and with per-sample positions the exact choice is redone at
// every pass; the Cycles race's 64-light scene (38 integrated) went from 10 to
// 42 samples per texel in 2 s and from 5.9 to 1.2 × Cycles' relMSE (balance)
// with 16 instead of 64. Delta lights: drawing them instead of tracing 26 each
// round changed nothing measurable there, so they stay traced up to 64.
constexpr int kManyDeltaLights = 64;
constexpr int kManyIntegratedLights = 16;
// Several local lights whose powers lie within this factor of each other are
// drawn uniformly (`uniform/solid-angle`); others by `defensive` selection.
// With perfect shape sampling and no occlusion, uniform selection between two
// lights contributing E1 = r·E2 adds ((r − 1)/(r + 1))² relative variance per
// sample: 0.36 at r = 4, which the better stratification and the robustness to
// occlusion measured on the race's scenes (r ≤ 2) outweigh; beyond, not.
constexpr double kComparablePower = 4.0;
// A world whose power (over a disk of the scene's radius) is at most this
// times the other integrated lights' together is a minor light: left to
// `bsdf` when the techniques have it (effect_plan.cpp, minor_world).
constexpr double kMinorWorldPower = 1.0;
// A world seen through emitters with at most this many meshes that do not
// emit (the receivers count) has its occluders drawn by their bounding boxes
// (EffectPlan::world_occluders): each draw then weighs every box face turned
// toward the point and draws a point on one of them by area.
constexpr int kFewWorldOccluders = 4;

// Texels in the shadow of most of their light draw kShadowedDraws times each
// count (DirectLightingSettings::shadowed_draws, set through `shadowed_draws`
// when given) among several comparable local lights: those whose centre does
// not see the middle points of lights that bring at least kShadowedShare of
// the light there unoccluded (point_setup.cpp, centre_in_shadow).
constexpr int kShadowedDraws = 4;
constexpr double kShadowedShare = 0.5;
// A world image drawn with MIS compensation (environment_map.h) gives the
// texels below its mean no density: `bsdf` must be among the techniques
// (with samples) and see the world, or the estimate would lose them. Throws
// std::invalid_argument saying so.
void require_compensation_covered(const Scene& scene, const std::vector<Technique>& techniques,
                                  const std::vector<int>& samples);

void default_techniques(const Scene& scene, std::vector<Technique>& techniques,
                        std::vector<int>& samples, int* shadowed_draws = nullptr);

}  // namespace omis
