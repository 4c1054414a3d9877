// Per-point light tables: the lights a table technique may pick at a point
// (or over a footprint's probes) with their probabilities and CDF, the
// defensive mixture, and the weights measured at a footprint's anchor.
#include "render/light_tables.h"

#include <cmath>
#include <limits>

#include "render/point_lighting_impl.h"

namespace omis {

// Whether technique k has a light to draw at (x, n). `tree` (and `uniform`,
// `power` among many lights) draws from the context's selectors, which need
// no per-point setup; otherwise a table over the lights that reach x is made
// here (`unoccluded`: by their exact unoccluded irradiance). A technique
// with no light to draw at x leaves the point's MIS system.
bool LightTables::make_at(int k, const Vec3& x, const Vec3& n) {
    const Technique& t = context_.settings.techniques[k];
    if (const LightSelector* s = context_.selector(t.selection)) {
        if (s->empty() || !s->may_reach(x, n)) return false;
        if (context_.integrated.size() > std::size_t(kManyIntegratedLights)) return true;
        for (std::uint32_t l : context_.integrated)
            if (sampler_applies(context_.scene.lights()[l], t.sampler, x, n)) return true;
        return false;
    }
    LightTable& c = tables_[std::size_t(k)];
    c.lights.clear();
    c.probability.clear();
    for (std::uint32_t l : context_.integrated) {
        const Light& light = context_.scene.lights()[l];
        if (!sampler_applies(light, t.sampler, x, n)) continue;
        double w = 1.0;
        if (t.selection == SelectionRule::Power) w = context_.power[l];
        if (t.selection == SelectionRule::Unoccluded || t.selection == SelectionRule::Defensive)
            w = unoccluded_irradiance(light, x, n);
        c.lights.push_back(l);
        c.probability.push_back(w);
    }
    // A light that reaches x but whose weight rounds to zero keeps a tiny share.
    normalise_weights(c.probability);
    cumulate(c.probability, c.cdf);
    if (t.selection == SelectionRule::Defensive) {
        reaches_.assign(c.lights.size(), 1);  // the table holds the lights that reach x
        mix_in_uniform(k);
    }
    return !c.lights.empty();
}

// The table covers a texel's footprint, not just its centre: a light that
// reaches the centre weighs what it does there (`unoccluded`: its unoccluded
// irradiance), one that reaches only some corners the mean over the probes
// (probes[0] is the centre), and every other light keeps the tiny share, so a
// light that reaches only the inside of the footprint is still drawn
// (unbiased wherever the technique is active). A table made at the centre
// alone dropped a light from every texel whose centre it did not reach — the
// rim of a spread light's reach, the plane of a one-sided light. Corners are
// probed only for lights that miss the centre: the weights cost per pass.
//
// Where the weights need no irradiance (`uniform`, `power`), the table is
// made from which probes each light reaches, which a kept texel has from its
// first pass: kept[i] = 1 + the probes light i weighs over (n_probes where
// it reaches the centre), 0 before. The weights then take the same sums in
// the same order: the same table, bit for bit, without probing again.
bool LightTables::make_over(int k, FootprintProbes& probes, std::uint8_t* kept) {
    const int n_probes = probes.count();
    const Technique& t = context_.settings.techniques[k];
    LightTable& c = tables_[std::size_t(k)];
    c.lights.clear();
    c.probability.clear();
    auto weight = [&](std::uint32_t l, const SurfacePoint& p) {
        if (t.selection == SelectionRule::Power) return context_.power[l];
        if (t.selection == SelectionRule::Unoccluded || t.selection == SelectionRule::Defensive)
            return unoccluded_irradiance(context_.scene.lights()[l], p.x, p.n);
        return 1.0;
    };
    const bool by_irradiance =
        t.selection == SelectionRule::Unoccluded || t.selection == SelectionRule::Defensive;
    bool any = false;
    reaches_.assign(context_.integrated.size(), 0);
    if (by_irradiance) kept = nullptr;
    const bool from_kept = kept && kept[0] != 0;
    for (std::size_t i = 0; i < context_.integrated.size(); ++i) {
        const std::uint32_t l = context_.integrated[i];
        const Light& light = context_.scene.lights()[l];
        double w = 0;
        if (from_kept) {
            const int reached = kept[i] - 1;
            if (reached == n_probes)
                w = weight(l, probes[0]);
            else  // the same at every probe: the centre's
                for (int j = 0; j < reached; ++j) w += weight(l, probes[0]) / n_probes;
            reaches_[i] = reached > 0;
        } else if (sampler_applies(light, t.sampler, probes[0].x, probes[0].n)) {
            w = by_irradiance ? centre_weight(i, probes[0]) : weight(l, probes[0]);
            reaches_[i] = 1;
            if (kept) kept[i] = std::uint8_t(1 + n_probes);
        } else {
            int reached = 0;
            for (int j = 1; j < n_probes; ++j)
                if (sampler_applies(light, t.sampler, probes[j].x, probes[j].n)) {
                    w += weight(l, probes[j]) / n_probes;
                    reaches_[i] = 1;
                    ++reached;
                }
            if (kept) kept[i] = std::uint8_t(1 + reached);
        }
        any = any || reaches_[i];
        c.lights.push_back(l);
        c.probability.push_back(w);
    }
    if (!any) return false;
    normalise_weights(c.probability);
    cumulate(c.probability, c.cdf);
    if (t.selection == SelectionRule::Defensive) mix_in_uniform(k);
    return true;
}

// `defensive` selection: technique k's table (unoccluded probabilities) becomes
// half that and half uniform over the lights that reach some probe, so a light
// the unoccluded weights undervalue — one shadowed where it is bright — keeps
// a fair share of a single technique's samples. Lights reaching no probe keep
// their tiny share (unbiased wherever the technique is active).
// With a world among the lights, the uniform part is kDefensiveShareWithWorld
// instead of half: the world is drawn by cosine over the whole hemisphere, and
// its draws are the noisy ones wherever it is partly hidden (each finds it with
// the probability of its visible cosine-weighted share: a skylight, a window),
// while a lamp's solid-angle draws are nearly exact where it is seen; half
// uniform gave the lamps as many draws as the world. Measured per sample
// (omis-module reproductions of the race's scenes, 64², optimal, 8–16 seeds,
// relMSE at 2/4/16/64/256 spp against a half): world_window (a skylit room,
// world 29× the lamp's power) 1.04/1.03/0.80/0.75/0.64 (a quarter:
// 0.91/0.92/0.85/0.83/0.78; none, i.e. `unoccluded`: 1.64/1.64/1.28/0.82/0.62,
// as a light drawn a few percent of the time is missed by most texels' first
// draws); emission_world with a world 10× as bright (then the main light, in
// the open) 0.41/0.48/0.49 at 4/16/256 spp (`unoccluded` 0.28/0.38/0.39).
void LightTables::mix_in_uniform(int k) {
    LightTable& c = tables_[std::size_t(k)];
    const std::vector<char>& reaches = reaches_;
    int reaching = 0;
    bool world = false;
    for (std::size_t i = 0; i < c.lights.size(); ++i) {
        reaching += reaches[i];
        world = world || context_.scene.lights()[c.lights[i]].type == LightType::World;
    }
    if (reaching == 0) return;
    const double uniform = world ? kDefensiveShareWithWorld : 0.5;
    double running = 0;
    for (std::size_t i = 0; i < c.lights.size(); ++i) {
        c.probability[i] =
            (1 - uniform) * c.probability[i] + (reaches[i] ? uniform / reaching : 0.0);
        running += c.probability[i];
        c.cdf[i] = running;
    }
    // The probabilities still sum to 1 (up to rounding): the CDF's end is exact.
    c.cdf.back() = 1.0;
}

// The anchor of the footprint being set up; its weights are kept while the
// next footprints name the same anchor (a block's texels, shaded in a row).
void LightTables::set_anchor(const Footprint* footprint) {
    Footprint::Anchor a;
    anchor_ = nullptr;
    if (!footprint || !footprint->table_anchor(a)) return;
    for (AnchorWeights& slot : anchors_) {
        const Footprint::Anchor& kept = slot.anchor;
        if (slot.used && kept.id == a.id && kept.at.x.x == a.at.x.x &&
            kept.at.x.y == a.at.x.y && kept.at.x.z == a.at.x.z && kept.at.n.x == a.at.n.x &&
            kept.at.n.y == a.at.n.y && kept.at.n.z == a.at.n.z) {
            anchor_ = &slot;
            return;
        }
    }
    anchor_ = &anchors_[next_anchor_slot_];
    next_anchor_slot_ = (next_anchor_slot_ + 1) % kAnchorSlots;
    anchor_->used = true;
    anchor_->anchor = a;
    anchor_->irradiance.assign(context_.integrated.size(), std::numeric_limits<double>::quiet_NaN());
}

// The `unoccluded` weight of integrated light i for a footprint whose centre
// it reaches: its unoccluded irradiance at the anchor when it reaches that,
// else at the centre. A function of the anchor and the centre only, so every
// pass and thread makes the same table.
double LightTables::centre_weight(std::size_t i, const SurfacePoint& centre) {
    const Light& light = context_.scene.lights()[context_.integrated[i]];
    if (anchor_) {
        double& w = anchor_->irradiance[i];
        if (std::isnan(w)) w = unoccluded_irradiance(light, anchor_->anchor.at.x, anchor_->anchor.at.n);
        if (w > 0) return w;
    }
    return unoccluded_irradiance(light, centre.x, centre.n);
}

std::vector<std::size_t> table_technique_offsets(const LightingContext& context,
                                                 std::size_t cells) {
    std::vector<std::size_t> at;
    std::size_t next = 0;
    for (const Technique& t : context.settings.techniques) {
        const bool table = !t.bsdf && !context.selector(t.selection);
        at.push_back(table ? next : ~std::size_t(0));
        if (table) next += cells;
    }
    return at;
}

void LightTables::restore(int k, const std::vector<std::uint32_t>& lights,
                          const std::vector<double>& probability) {
    LightTable& c = tables_[std::size_t(k)];
    c.lights = lights;
    c.probability = probability;
    cumulate(c.probability, c.cdf);
}

std::size_t LightTables::longest() const {
    std::size_t n = 0;
    for (const LightTable& c : tables_) n = std::max(n, c.lights.size());
    return n;
}

}  // namespace omis
