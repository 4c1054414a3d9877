// LightingContext: a lighting job's validated settings, effect plan, lights
// by role, selectors and the per-point state a bake's passes keep.
#include <mutex>
#include <stdexcept>
#include <string>

#include "render/point_lighting_impl.h"

namespace omis {

namespace {

void validate(const Scene& scene, const DirectLightingSettings& s) {
    if (!scene.committed())
        throw std::logic_error("scene: not committed (call commit before lighting)");
    if (s.techniques.size() != s.samples.size())
        throw std::invalid_argument("samples: expected one count per technique (" +
                                    std::to_string(s.techniques.size()) + "), got " +
                                    std::to_string(s.samples.size()));
    if (s.techniques.size() > kMaxMisTechniques)
        throw std::invalid_argument("techniques: at most " +
                                    std::to_string(kMaxMisTechniques));
    for (int n : s.samples)
        if (n < 0) throw std::invalid_argument("samples: counts must not be negative");
    if (s.rounds < 1) throw std::invalid_argument("rounds: must be at least 1");
    if (s.streams < 1 || s.streams > kMaxSampleStreams)
        throw std::invalid_argument("streams: must lie in [1, " +
                                    std::to_string(kMaxSampleStreams) + "], got " +
                                    std::to_string(s.streams));
    // Draw indices (round × count + j) and per-point totals are ints.
    long long per_point = 0;
    for (int n : s.samples) per_point += (long long)n * s.rounds;
    if (per_point > std::numeric_limits<int>::max())
        throw std::invalid_argument("samples: " + std::to_string(per_point) +
                                    " draws per point (counts × rounds) exceed the limit of " +
                                    std::to_string(std::numeric_limits<int>::max()));
    for (std::size_t i = 0; i < s.techniques.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (s.techniques[i] == s.techniques[j])
                throw std::invalid_argument("techniques: '" + s.techniques[i].name() +
                                            "' is listed twice");
    // Image-based world: a compensated map needs `bsdf` (effect_plan.h).
    require_compensation_covered(scene, s.techniques, s.samples);
}

}  // namespace

LightingContext::LightingContext(const Scene& scene_, const DirectLightingSettings& s)
    : scene((validate(scene_, s), scene_)),
      settings(s),
      plan(plan_effects(scene_, s.techniques, s.samples, s.points_on_mesh)),
      power(scene_.light_powers()) {
    for (std::size_t k = 0; k < settings.techniques.size(); ++k)
        if (plan.enabled[k]) techniques.push_back(int(k));
    for (std::uint32_t l = 0; l < scene.lights().size(); ++l) {
        const Light& light = scene.lights()[l];
        // A world left to `bsdf` is no light technique's to select.
        const bool bsdf_only = plan.world_by_bsdf && light.type == LightType::World;
        if (!bsdf_only) (light.is_delta() ? delta : integrated).push_back(l);
        if (scene.lights().size() <= kMaxTinyShapeTable)
            tiny_shapes.push_back(tiny_shape_of(light));
    }
    // Few lights: `uniform` and `power` keep their per-point tables over the
    // lights that reach x (no draw wasted on the others).
    const bool many = integrated.size() > std::size_t(kManyIntegratedLights);
    for (int k : techniques) {
        const Technique& t = settings.techniques[k];
        if (t.bsdf || (!many && t.selection != SelectionRule::Tree)) continue;
        if (t.selection == SelectionRule::Uniform && !uniform_selector)
            uniform_selector = &scene.light_selector(LightSelector::Kind::Uniform, false);
        if (t.selection == SelectionRule::Power && !power_selector)
            power_selector = &scene.light_selector(LightSelector::Kind::Power, false);
        if (t.selection == SelectionRule::Tree && !tree_selector)
            tree_selector = &scene.light_selector(LightSelector::Kind::Tree, false);
    }
    if (plan.sample_delta_lights)
        delta_selector = &scene.light_selector(LightSelector::Kind::Tree, true);
    keeps_texel_tables = std::any_of(
        settings.techniques.begin(), settings.techniques.end(), [](const Technique& t) {
            return !t.bsdf && t.selection != SelectionRule::Uniform &&
                   t.selection != SelectionRule::Power;
        });
}

void LightingContext::keep_shadow_verdicts(std::size_t points) {
    if (settings.shadowed_draws > 1 && settings.shadowed_draws <= 255)  // a byte each
        shadow_verdicts.assign(points, 0);
}

void LightingContext::keep_region_radii(std::size_t points) {
    // PointLighting's set_region makes a region only for selectors' draws.
    const bool selectors = std::any_of(techniques.begin(), techniques.end(), [&](int k) {
        return !settings.techniques[k].bsdf && selector(settings.techniques[k].selection);
    });
    if (selectors) region_radii.assign(points, -1.0);
}

namespace {

// The kept branching of the last context to end, for the next one to take.
// Its block (5.2 MB at 128²) was otherwise at times handed back to the system
// at a bake's end and faulted in anew by the next one: 16-20 ms of a 0.05 s
// budget in Blender, on emissive_mesh at 128² (bench/results/budgets.txt).
struct SpareBranching {
    std::mutex mutex;
    std::vector<LightSelector::KeptNode> nodes;
};
// Never destroyed: a context may end after static destruction has begun
// (a Python object freed at exit).
SpareBranching& spare_branching() {
    static SpareBranching* spare = new SpareBranching;
    return *spare;
}

}  // namespace

LightingContext::~LightingContext() {
    if (region_branching.capacity() == 0) return;
    SpareBranching& spare = spare_branching();
    std::lock_guard<std::mutex> lock(spare.mutex);
    if (region_branching.capacity() > spare.nodes.capacity()) spare.nodes.swap(region_branching);
}

void LightingContext::keep_region_branching(std::size_t points, std::size_t max_nodes) {
    // Only the tree's memo walks nodes (set_region's memo, for its draws).
    const bool tree = std::any_of(techniques.begin(), techniques.end(), [&](int k) {
        return !settings.techniques[k].bsdf &&
               settings.techniques[k].selection == SelectionRule::Tree;
    });
    if (!tree || points == 0) return;
    region_nodes =
        std::min(max_nodes, kRegionBranchingBytes / sizeof(LightSelector::KeptNode) / points);
    if (region_nodes == 0) return;
    {
        SpareBranching& spare = spare_branching();
        std::lock_guard<std::mutex> lock(spare.mutex);
        if (spare.nodes.capacity() > region_branching.capacity()) region_branching.swap(spare.nodes);
    }
    region_branching.assign(points * region_nodes, {});
}

void LightingContext::keep_table_reach(std::size_t points) {
    if (keeps_texel_tables) return;  // their entries hold the tables
    std::size_t tables = 0;
    for (const Technique& t : settings.techniques) tables += !t.bsdf && !selector(t.selection);
    table_reach.index_points(points, tables * integrated.size());
}

void LightingContext::keep_draw_counts(std::size_t points) {
    std::size_t tables = 0;  // light techniques that draw from per-point tables
    for (const Technique& t : settings.techniques) tables += !t.bsdf && !selector(t.selection);
    draw_counts.index_points(points, tables * std::size_t(settings.streams) * integrated.size());
}

const LightSelector* LightingContext::selector(SelectionRule selection) const {
    switch (selection) {
        case SelectionRule::Uniform:
            return uniform_selector && !uniform_selector->empty() ? uniform_selector : nullptr;
        case SelectionRule::Power:
            return power_selector && !power_selector->empty() ? power_selector : nullptr;
        case SelectionRule::Tree: {
            static const LightSelector kNoLights;  // a tree technique never built: draws nothing
            return tree_selector ? tree_selector : &kNoLights;
        }
        case SelectionRule::Unoccluded:
        case SelectionRule::Defensive: return nullptr;
    }
    return nullptr;
}

}  // namespace omis
