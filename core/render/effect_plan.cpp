#include "render/effect_plan.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace omis {
namespace {

bool has_planar_projection(const Light& l) {
    switch (l.type) {
        case LightType::Rect:
        case LightType::Ellipse:
        case LightType::Triangle: return true;
        case LightType::Point:
        case LightType::Spot: return l.radius > 0;
        default: return false;
    }
}

// Widest extent of a planar light (rect diagonal, ellipse major diameter,
// longest triangle edge); 0 for other lights.
double planar_extent(const Light& l) {
    switch (l.type) {
        case LightType::Rect: return length(l.rect.edge_u + l.rect.edge_v);
        case LightType::Ellipse:
            return 2 * std::max(length(l.ellipse.axis_a), length(l.ellipse.axis_b));
        case LightType::Triangle: {
            const TriangleLight& t = l.triangle;
            return std::max({length(t.p1 - t.p0), length(t.p2 - t.p1), length(t.p0 - t.p2)});
        }
        default: return 0;
    }
}

// The diagonal of an emissive mesh's bounding box.
double mesh_extent(const Mesh& mesh) {
    if (mesh.positions.empty()) return 0;
    Vec3 lo = mesh.positions[0], hi = lo;
    for (const Vec3& p : mesh.positions) {
        lo = component_min(lo, p);
        hi = component_max(hi, p);
    }
    return length(hi - lo);
}

// A light's power: the scene's, made at commit (Scene::light_powers), else
// made here.
double light_power(const Scene& scene, std::size_t light) {
    const std::vector<double>& powers = scene.light_powers();
    return light < powers.size() ? powers[light]
                                 : scene.lights()[light].power(scene.bounding_radius());
}

// Whether a scene's integrated lights are all local (no sun, no world) and of
// comparable power: the largest at most kComparablePower times the smallest.
// Uniform selection then costs little where the unoccluded weights are right
// and wins where occlusion makes them wrong. Distant lights' power depends on
// the scene's size and does not compare with a lamp's; nor does a mesh
// light's, which leaves every way (the emissive_mesh race scene's sphere
// and square lamp, bench_emitters --only race, relative variance a sample
// times the time: uniform 0.46, defensive 0.25, unoccluded 0.21).
// With `without_world`, a world is left out of the comparison (a minor world
// is left to `bsdf`: minor_world).
bool comparable_local_lights(const Scene& scene, bool without_world) {
    double lo = 0, hi = 0;
    bool any = false;
    for (std::size_t i = 0; i < scene.lights().size(); ++i) {
        const Light& l = scene.lights()[i];
        if (l.is_delta() || (without_world && l.type == LightType::World)) continue;
        if (l.type == LightType::Sun || l.type == LightType::World || l.type == LightType::Mesh)
            return false;
        const double p = light_power(scene, i);
        lo = any ? std::min(lo, p) : p;
        hi = any ? std::max(hi, p) : p;
        any = true;
    }
    return any && lo > 0 && hi <= kComparablePower * lo;
}

// Whether a scene's world, a constant radiance over the hemisphere, is left to
// `bsdf` alone (given a `bsdf` technique), out of the light techniques'
// selection, as Cycles leaves a constant world to its BSDF rays: when it is a
// minor light, its power at most kMinorWorldPower times the other integrated
// lights' together, with at most kManyIntegratedLights lights in all (the
// shared selectors of many lights hold the world too). Cosine sampling is
// the world's own sampler for a Lambert receiver, so `bsdf` integrates it as
// well as a light technique would, and the light technique's draws go to the
// emitters that matter. A world that is the main light stays in the
// selection, where `defensive` gives it most draws: a world seen through an
// opening is noisy by cosine sampling and needs them. Measured per sample
// against Cycles (bench_cycles --equal-samples, 128², optimal, relMSE ratio):
// emission_world (world 0.34× the emitter's power) 1.72 → 1.45 left to bsdf;
// world_window (a skylit room, world 29× the lamp's) 1.47 → 3.37 left to bsdf.
bool minor_world(const Scene& scene) {
    int integrated = 0;
    double world = -1, others = 0;
    for (std::size_t i = 0; i < scene.lights().size(); ++i) {
        const Light& l = scene.lights()[i];
        if (l.is_delta()) continue;
        ++integrated;
        const double p = light_power(scene, i);
        if (l.type == LightType::World && l.visible_to_bsdf)
            world = p;
        else
            others += p;
    }
    return world >= 0 && integrated >= 2 && integrated <= kManyIntegratedLights &&
           world <= kMinorWorldPower * others;
}

// minor_world, and the techniques include `bsdf` (which then covers every
// direction: unbiased) and no `tree` (its selector holds every light).
bool world_left_to_bsdf(const Scene& scene, const std::vector<Technique>& techniques,
                        const std::vector<int>& samples) {
    if (!minor_world(scene)) return false;
    bool bsdf = false;
    for (std::size_t k = 0; k < techniques.size(); ++k) {
        if (k < samples.size() && samples[k] <= 0) continue;
        if (techniques[k].bsdf) bsdf = true;
        else if (techniques[k].selection == LightSelection::Tree) return false;
    }
    return bsdf;
}

// Whether a world left to `bsdf` (minor_world, world_left_to_bsdf) is seen
// through emissive triangles: occluding geometry, and emissive triangles whose
// radiance is at least the world's in every channel (so the emitters' part
// L_e − L_w of the integrand stays non-negative), every integrated light
// casting shadows and seen by BSDF rays (one closest hit then tells what a
// direction meets first; no light is then hidden from BSDF rays, and some
// light casts shadows: the plan's shadow_rays is has_occluders()).
// Measured per sample on the emission_world reproduction (64², optimal,
// 4 seeds): the world's part alone, 32 cosine draws, relMSE 2.6e-4 with the
// quad and the box as occluders, 1.5e-4 with the box alone.
bool world_seen_through_emitters(const Scene& scene) {
    if (!scene.geometry().has_occluders()) return false;
    const Light* world = nullptr;
    for (const Light& l : scene.lights())
        if (l.type == LightType::World) world = &l;
    if (!world) return false;
    bool triangles = false;
    for (const Light& l : scene.lights()) {
        if (l.is_delta()) continue;
        if (!l.cast_shadow || !l.visible_to_bsdf) return false;
        // Emissive meshes: a light per triangle, or one mesh light.
        if (l.type != LightType::Triangle && l.type != LightType::Mesh) continue;
        triangles = true;
        if (!(l.emission.x >= world->emission.x && l.emission.y >= world->emission.y &&
              l.emission.z >= world->emission.z && l.two_sided))
            return false;
    }
    return triangles;
}

// The world seen through emitters (world_seen_through_emitters) around at
// most kFewWorldOccluders meshes that do not emit: their bounding boxes, else
// none. Where something does hide the world, cosine draws see it as Bernoulli
// noise over the whole hemisphere; drawn inside the boxes' outlines (directions
// whose first hit does not emit lie in their own mesh's box), the hidden share
// varies only with the cosine where a box's mesh fills it. Measured per sample
// on emission_world (a box and the receiver; omis optimal relMSE ÷ Cycles' at
// 16/64/256 samples): 1.23/1.30/1.35 → 0.53/0.44/0.48, at 1.13× the time a
// round (bench/results/error_sources.txt, 2026-12-01).
std::vector<EffectPlan::OccluderBox> world_occluders(const Scene& scene) {
    std::vector<EffectPlan::OccluderBox> boxes;
    const std::vector<Mesh>& meshes = scene.geometry().meshes();
    for (std::uint32_t m = 0; m < meshes.size(); ++m) {
        const Mesh& mesh = meshes[m];
        if (mesh.is_emissive() || mesh.triangles.empty()) continue;
        if (int(boxes.size()) == kFewWorldOccluders) return {};
        EffectPlan::OccluderBox box{m, mesh.positions[mesh.triangles[0][0]],
                                    mesh.positions[mesh.triangles[0][0]]};
        for (const auto& t : mesh.triangles)
            for (std::uint32_t v : t) {
                const Vec3& q = mesh.positions[v];
                box.lo = component_min(box.lo, q);
                box.hi = component_max(box.hi, q);
            }
        boxes.push_back(box);
    }
    return boxes;
}

// Whether every point shaded lies on the flat mesh `points_mesh` and every
// mesh of the scene lies in its plane: a ray from such a point (offset to
// the side it leaves toward) moves away from the plane and meets no surface,
// so no light can be shadowed there and no shadow ray need be traced (a lone
// floor under lamps: the race's area, area_round, point_spot). Within a
// millionth of the scene's radius: a tilted plane's float vertices stray
// ~1e-7 of their size from it, and a surface closer to the plane than the
// tolerance is z-fighting with it, where a traced ray's verdict is the
// rounding's too. An id past the meshes (~0u: points anywhere) says no.
bool nothing_can_occlude(const Scene& scene, std::uint32_t points_mesh) {
    const std::vector<Mesh>& meshes = scene.geometry().meshes();
    if (points_mesh >= meshes.size()) return false;
    const Mesh& floor = meshes[points_mesh];
    // The plane of its largest triangle (the best-conditioned normal).
    std::uint32_t largest = 0;
    double largest_area = 0;
    for (std::uint32_t t = 0; t < floor.num_triangles(); ++t)
        if (const double a = floor.triangle_area(t); a > largest_area) {
            largest = t;
            largest_area = a;
        }
    if (!(largest_area > 0)) return false;
    const Vec3 normal = floor.geometric_normal(largest);
    const Vec3 origin = floor.positions[floor.triangles[largest][0]];
    const double tolerance = 1e-6 * scene.bounding_radius();
    for (const Mesh& mesh : meshes)
        for (const Vec3& p : mesh.positions)
            if (!(std::abs(dot(p - origin, normal)) <= tolerance)) return false;
    return true;
}

}  // namespace

EffectPlan plan_effects(const Scene& scene, const std::vector<Technique>& techniques,
                        const std::vector<int>& samples, std::uint32_t points_mesh) {
    EffectPlan plan;
    plan.techniques = techniques;
    plan.samples = samples;
    bool any_bsdf_visible = false, any_projectable = false, any_shadow = false;
    for (const Light& l : scene.lights()) {
        ++plan.lights_by_type[int(l.type)];
        any_shadow = any_shadow || l.cast_shadow;
        if (l.is_delta()) {
            ++plan.delta_lights;
            continue;
        }
        ++plan.integrated_lights;
        any_bsdf_visible = any_bsdf_visible || l.visible_to_bsdf;
        plan.bsdf_invisible_lights = plan.bsdf_invisible_lights || !l.visible_to_bsdf;
        any_projectable = any_projectable || has_planar_projection(l);
    }
    plan.shadow_rays = scene.geometry().has_occluders() && any_shadow &&
                       !nothing_can_occlude(scene, points_mesh);
    plan.world_by_bsdf = world_left_to_bsdf(scene, techniques, samples);
    plan.world_through_emitters = plan.world_by_bsdf && world_seen_through_emitters(scene);
    if (plan.world_through_emitters) plan.world_occluders = world_occluders(scene);
    if (plan.delta_lights > kManyDeltaLights) {
        plan.sample_delta_lights = true;
        for (std::size_t k = 0; k < techniques.size() && k < samples.size(); ++k)
            plan.delta_samples += std::max(0, samples[k]);
        plan.delta_samples = std::max(1, plan.delta_samples);
    }

    for (std::size_t k = 0; k < techniques.size(); ++k) {
        const Technique& t = techniques[k];
        std::string why;
        if (k < samples.size() && samples[k] <= 0)
            why = "no samples requested";
        else if (t.bsdf && !any_bsdf_visible)
            why = plan.integrated_lights ? "every light is hidden from BSDF rays"
                                         : "no light a BSDF ray can hit (delta lights only)";
        else if (!t.bsdf && plan.integrated_lights == 0)
            why = "no light with area or angle to sample (delta lights only)";
        else if (!t.bsdf && t.sampler == ShapeSampler::Parallel && !any_projectable)
            why = "no light with a planar region to project";
        plan.enabled.push_back(why.empty());
        if (why.empty() && !t.bsdf && t.selection == LightSelection::Tree)
            why = "applies (light tree: O(log L) selection over " +
                  std::to_string(plan.integrated_lights) + " light(s))";
        else if (why.empty() && !t.bsdf &&
                 (t.selection == LightSelection::Unoccluded ||
                  t.selection == LightSelection::Defensive) &&
                 plan.integrated_lights > kManyIntegratedLights)
            why = "applies (exact per-light weights: cost grows with the " +
                  std::to_string(plan.integrated_lights) + " lights; `tree` does not)";
        plan.why.push_back(why.empty() ? "applies (per point: lights above the horizon)" : why);
        plan.mis_system = plan.mis_system || why.empty();
    }
    return plan;
}

std::string EffectPlan::to_string() const {
    std::ostringstream s;
    s << "effect plan\n  lights:";
    bool any = false;
    for (int t = 0; t < kLightTypes; ++t)
        if (lights_by_type[t]) {
            s << ' ' << light_type_name(LightType(t)) << "×" << lights_by_type[t];
            any = true;
        }
    if (!any) s << " none";
    s << "\n  integrated by MIS: " << integrated_lights << " light(s); delta (one shadow ray"
      << " each, outside MIS): " << delta_lights << "\n  shadow rays: "
      << (shadow_rays ? "yes" : "no (nothing can occlude the points)") << "\n  MIS system per point: "
      << (mis_system ? "yes" : "no") << "\n";
    if (const int meshes = lights_by_type[int(LightType::Mesh)])
        s << "  emissive meshes drawn as one light each: " << meshes
          << " (directions toward the mesh's bounding sphere; the first hit tells if it is seen)\n";
    if (sample_delta_lights)
        s << "  delta lights: " << delta_lights << ", too many for a shadow ray each: "
          << delta_samples << " per round drawn by a light tree (unbiased)\n";
    if (bsdf_invisible_lights)
        s << "  some lights are hidden from BSDF rays: light techniques integrate them alone\n";
    if (world_by_bsdf)
        s << "  the world is left to bsdf (as Cycles): light techniques draw the other lights\n";
    if (world_through_emitters)
        s << "  the world is seen through emissive triangles (bsdf alone), which emit L_e - L_w\n";
    if (!world_occluders.empty())
        s << "  ... around " << world_occluders.size()
          << " mesh(es) that do not emit: bsdf draws toward their bounding boxes\n";
    s << "  techniques:\n";
    for (std::size_t k = 0; k < techniques.size(); ++k) {
        s << "    " << (enabled[k] ? "+ " : "- ") << techniques[k].name();
        if (k < samples.size()) s << " ×" << samples[k];
        s << ": " << why[k] << "\n";
    }
    return s.str();
}

void default_techniques(const Scene& scene, std::vector<Technique>& techniques,
                        std::vector<int>& samples, int* shadowed_draws) {
    techniques.clear();
    samples.clear();
    if (shadowed_draws) *shadowed_draws = 1;
    int integrated = 0;
    bool world = false, huge = false;
    for (const Light& l : scene.lights()) {
        if (l.is_delta()) continue;
        ++integrated;
        world = world || l.type == LightType::World;
        // A light as wide as the scene covers much of the hemisphere of points
        // near it and crosses their horizon; uniform solid angle then spends its
        // draws where cos θ is small. Measured on disks 5 cm and 1 m under
        // lights 1 m and 60 m wide (16 rounds, optimal weights): adding `bsdf`
        // cut the per-point standard deviation 3× and 11×.
        huge = huge || planar_extent(l) >= scene.bounding_radius();
    }
    // An emissive mesh is huge as a whole where its triangles are not.
    for (const Mesh& mesh : scene.geometry().meshes())
        if (mesh.is_emissive()) huge = huge || mesh_extent(mesh) >= scene.bounding_radius();
    auto add = [&](const char* name, int count) {
        techniques.push_back(*parse_technique(name));
        samples.push_back(count);
    };
    if (integrated == 0) return;
    // A minor world among few other lights is left to `bsdf`
    // (world_left_to_bsdf); the light technique below chooses among the others.
    const bool world_to_bsdf = minor_world(scene);
    const int lamps = integrated - (world_to_bsdf ? 1 : 0);
    // One light: one technique, not a pair: each technique draws from its own
    // low-discrepancy sequence, and two sequences of N/2 points converge far
    // slower than one of N on these smooth integrands. Measured per sample on
    // 32² texel bakes (relative variance over seeds, balance and optimal
    // alike): solid angle alone against solid angle + area 30× lower on one
    // rect, 6× on a disk 3 cm above the receiver, 2.6× on a sun (whose two
    // samplers are one).
    if (lamps == 1) {
        add("uniform/solid-angle", 1);
    } else if (integrated > kManyIntegratedLights) {
        // Many emitters: the exact unoccluded weights would cost O(L) per
        // point; the light tree picks by bounds in O(log L). One technique,
        // as with one light: one sequence of N samples converges faster than
        // three of N/3. Measured per sample (bench/bench_emitters_quality.py:
        // relative variance over seeds of 48² texel bakes at 32 samples):
        // the emissive_mesh race scene 1.6× lower than tree + power + bsdf
        // (tree + bsdf: 1.3× higher than that), the many_lights grid 2.1×
        // lower than tree + power, an emissive sphere 5 cm above the
        // receiver 2.7× lower. Cosine sampling joins for a world and for huge
        // lights (below): under a 1.6 m emissive panel 25 cm above the
        // receiver, tree + bsdf had half the variance of the tree alone.
        add("tree/solid-angle", 1);
        if (world) add("bsdf", 1);
    } else if (comparable_local_lights(scene, world_to_bsdf)) {
        // Several local lights of about the same power: each drawn equally
        // often. Every light then keeps an equal, well-stratified share of
        // the one sequence, and no light is starved where occlusion makes
        // the unoccluded weights wrong. Measured per sample against Cycles
        // (64 spp, 128², optimal; bench_cycles scenes): demo_room 1.68 →
        // 1.01, area 1.57 → 0.44, area_round 0.19 → 0.09, spread_walls
        // unchanged; `unoccluded` alone was worse than `defensive` on all.
        add("uniform/solid-angle", 1);
        // Texels whose centre sees no light's middle point (the demo room's
        // floor under its table, lit by slivers of the lights: a heavy tail)
        // held ~85 % of demo_room's relMSE on 7.5 % of its texels; drawing
        // there 4× as often (a deterministic probe, unbiased) took its relMSE
        // at 16/64 samples from 1.35e-2 to 3.0e-3 and 1.61e-3 to 4.2e-4
        // (10 seeds) for ~1.35× the CPU time (bench/results/error_sources.txt).
        // Also where only the lights that bring most of the light hide their
        // middles (kShadowedShare): shared_image's square light behind the
        // box, beside a sphere light that still lights the texel, 0.97 →
        // 0.19× Cycles' relMSE at equal samples (16–256 spp).
        if (shadowed_draws) *shadowed_draws = kShadowedDraws;
    } else {
        // Several lights of unequal power, or a sun among them: one
        // technique again, selecting half by unoccluded contribution (the
        // paper's "trained" technique) and half uniformly, so lights that
        // occlusion hides from the unoccluded weights keep their share
        // (`unoccluded` alone starved the demo room's floor under its table).
        // One sequence of N samples instead of a pair's two of N/2: see
        // bench_cycles' error per sample (README, issue 9). With a world in
        // the selection the uniform part is a tenth, not half (its cosine
        // draws are the noisy ones: direct_lighting.cpp, mix_in_uniform).
        add("defensive/solid-angle", 1);
    }
    // The world left to `bsdf`; huge lights are what cosine sampling is good
    // at (a world in the light techniques is drawn by cosine already, and
    // among many emitters `bsdf` joins the tree for the world above).
    const bool has_bsdf = integrated > kManyIntegratedLights && world;
    // One cosine draw a round, also for a world seen through emitters
    // (world_seen_through_emitters): there the light draws carry the
    // penumbrae of the emitters, which two cosine draws a round starved.
    // Emission_world (128², optimal, bench_cycles --equal-samples, 2 seeds,
    // relMSE ÷ Cycles' at 16/64/256 samples): two per round 1.68/1.75/1.89,
    // one 1.27/1.30/1.29 (1 light : 2 cosine drew a third of the samples
    // from the light: 2.3× Cycles' error beside the box, 0.5× elsewhere).
    // A round of one each costs 1.2× a round of one and two per sample (CPU
    // time, 5 alternated bakes at 96/384/1024 samples): 0.80–0.90× the
    // relMSE at equal time. Two light draws to one cosine: 2.0/2.3/2.5.
    // (Two cosine draws, ce01fcb, rested on single race runs.)
    if (!has_bsdf && (world_to_bsdf || huge)) add("bsdf", 1);
}

}  // namespace omis
