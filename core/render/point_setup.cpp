// A point's setup before its samples: which techniques take part and their
// light tables (kept per texel for later passes), the shadow probe, and the
// selector's region.
#include "render/point_lighting_impl.h"

namespace omis {

void PointLighting::Impl::choose_active(std::uint64_t point, FootprintProbes& probes,
                                        const Footprint* footprint, Active& active) {
    // Light choice (which lights, with what probability) is made once per
    // point and kept for every sample of the footprint: per-point tables over
    // the centre and corners together (LightTables::make_over); selectors at the
    // centre — or, where no light applies there, at the first corner where
    // one does. A fixed choice is a valid technique at every position:
    // its density at a sample's own position x_s is Σ_l P(l) p_l(ω | x_s),
    // which is what technique_pdf evaluates, so the combination stays
    // unbiased; a light that applies nowhere it was probed is left to the
    // other techniques there.
    const int n_probes = probes.count();
    // Anchored weights serve only per-point tables by unoccluded irradiance;
    // an anchor costs a slot per integrated light (16k on an emissive mesh).
    bool irradiance_tables = false;
    for (int k : p_.techniques) {
        const Technique& t = p_.settings.techniques[k];
        irradiance_tables = irradiance_tables ||
                            (!t.bsdf && !p_.selector(t.selection) &&
                             (t.selection == SelectionRule::Unoccluded ||
                              t.selection == SelectionRule::Defensive));
    }
    tables_.set_anchor(irradiance_tables ? footprint : nullptr);
    if (p_.settings.shadowed_draws > 1) active.draws_per_count = draws_per_count_at(point, probes[0]);
    for (int k : p_.techniques) {
        const Technique& t = p_.settings.techniques[k];
        if (!t.bsdf) {
            bool reaches = false;
            if (footprint && !p_.selector(t.selection)) {
                std::uint8_t* kept = p_.table_reach.of(point);
                reaches = tables_.make_over(k, probes, kept ? kept + kept_reach_at_[k] : nullptr);
            } else {
                for (int i = 0; i < n_probes && !reaches; ++i)
                    reaches = tables_.make_at(k, probes[i].x, probes[i].n);
            }
            if (!reaches) continue;
            active.lights.push_back(k);
            active.light_mask |= std::uint64_t(1) << k;
        }
        active.all.push_back(k);
        active.mask |= std::uint64_t(1) << k;
    }
}

// The verdict is kept in the context's shadow_verdicts (a byte a texel) where
// the job keeps them, else probed again: the probe is deterministic. (A
// TexelTables entry per texel for it cost more: 128², 8 spp, CPU: area
// 1.3-1.5x with no texel shadowed, demo_room 1.65x.)
int PointLighting::Impl::draws_per_count_at(std::uint64_t point, const SurfacePoint& centre) {
    std::uint8_t* kept = point < p_.shadow_verdicts.size() ? &p_.shadow_verdicts[point] : nullptr;
    if (kept && *kept) return *kept;
    const int m = centre_in_shadow(centre) ? p_.settings.shadowed_draws : 1;
    if (kept) *kept = std::uint8_t(m);
    return m;
}

// Whether the integrated lights whose middle point (an area draw at u = ½, ½:
// the middle of the shape, or of the part a spread lets reach p) p does not
// see carry at least kShadowedShare of the light those middle points bring
// unoccluded, each weighed by its draw's f / pdf (a one-point estimate of the
// light's unoccluded irradiance at p); true too where no light's middle
// brings any. Deterministic, so a draw count chosen by it is fixed per texel
// before any of its samples. Not only where every middle is hidden: in
// shared_image the box hides the square light's middle from 15 % of the
// texels, where the sphere light alone would have kept them at one draw a
// count; the square's penumbra there (2 % of the texels, 5–20 % of the mean)
// held 56 % of the relMSE (bench/results/error_sources.txt).
// By area and that light alone, not by solid angle and every light along the
// direction: the spherical rectangle's construction and the emitter query
// cost ~3.3k instructions of a probe's ~4.3k a light on the race's rect
// lights (callgrind, 128² demo_room: the probe took 1.5 samples' work a
// texel, ~28 % of a 3-spp bake). The brightest middle is traced first and
// the rays stop once the verdict is settled (one ray where that light alone
// carries more than the share and is seen).
bool PointLighting::Impl::centre_in_shadow(const SurfacePoint& p) {
    std::vector<MiddlePoint>& middles = middles_scratch_;
    middles.clear();
    double total = 0;
    for (std::uint32_t l : p_.integrated) {
        const auto s =
            sample_light(p_.scene.lights()[l], ShapeSampler::Area, p.x, p.n, 0.5, 0.5);
        if (!s || !(s->pdf > 0)) continue;
        const auto u = integrand_.unoccluded(l, p.x, p.n, s->dir);
        if (!u) continue;
        const double weight = luminance(u->radiance) * u->cosine_factor / s->pdf;
        if (!(weight > 0)) continue;
        if (!p_.plan.shadow_rays) return false;  // nothing hides it: settled
        middles.push_back({weight, l, s->dir, u->distance});
        total += weight;
    }
    std::sort(middles.begin(), middles.end(),
              [](const MiddlePoint& a, const MiddlePoint& b) { return a.weight > b.weight; });
    double seen = 0, hidden = 0;
    for (const MiddlePoint& m : middles) {
        (integrand_.occluded(m.light, p.x, p.ng, m.dir, m.distance) ? hidden : seen) += m.weight;
        if (hidden >= kShadowedShare * total) return true;
        if (seen > (1 - kShadowedShare) * total) return false;
    }
    return true;
}

// The ball about the centre through the footprint's farthest corner holds
// the whole footprint where it is flat (a parallelogram); a sample outside
// it (a footprint bent over a crease) is drawn for its own position.
// Only selectors draw with it: without them the corners are not made here.
void PointLighting::Impl::set_region(std::uint64_t point, FootprintProbes& probes) {
    const SurfacePoint& centre = probes[0];
    region_ = {centre.x, centre.n, 0.0};
    region_memo_.keep_in(p_.region_branching_of(point), p_.region_nodes);
    if (probes.count() == 1) return;
    double* kept = point < p_.region_radii.size() ? &p_.region_radii[point] : nullptr;
    if (kept && *kept >= 0) {
        region_.radius = *kept;
        return;
    }
    bool selectors = false;
    for (int k : p_.techniques)
        selectors = selectors || (!p_.settings.techniques[k].bsdf &&
                                  p_.selector(p_.settings.techniques[k].selection));
    if (!selectors) return;
    double r2 = 0;
    for (int j = 1; j < probes.count(); ++j) {
        const Vec3 d = probes[j].x - centre.x;
        r2 = std::max(r2, dot(d, d));
    }
    region_.radius = std::sqrt(r2);
    if (kept) *kept = region_.radius;
}

// Sampling and the densities at a sample both ask here with the sample's x,
// so both use the same rule there: the region's pmfs inside it, x's own
// outside. Either is a valid selection at x (light_selection.h).
LightSelector::Receiver PointLighting::Impl::receiver_at(const Vec3& x, const Vec3& n,
                                                         LightSelector::Memo*& memo) {
    const Vec3 d = x - region_.x;
    if (region_.radius > 0 && dot(d, d) <= region_.radius * region_.radius) {
        memo = &region_memo_;
        return region_;
    }
    memo = &memo_;
    return {x, n, 0.0};
}

void PointLighting::Impl::active_for(std::uint64_t point, bool keep, const SurfacePoint& centre,
                                     const Footprint* footprint, Active& active) {
    FootprintProbes probes(centre, footprint);
    set_region(point, probes);
    TexelTables& kept = p_.texel_tables;
    keep = keep && !cheap_tables_;
    if (keep)
        if (const TexelTables::Entry* entry = kept.find(point)) {
            restore(*entry, active);
            if (p_.settings.shadowed_draws > 1)
                active.draws_per_count = draws_per_count_at(point, centre);
            return;
        }
    ScopedTimer setup(keep && setup_timing_ && setup_timing_->on ? &setup_timing_->kept_setup
                                                                  : nullptr);
    choose_active(point, probes, footprint, active);
    if (!keep) return;
    TexelTables::Entry entry;
    entry.mask = active.mask;
    entry.light_mask = active.light_mask;
    auto uses_table = [&](int k) { return !p_.selector(p_.settings.techniques[k].selection); };
    // One allocation of the exact size (no regrowth; bytes_of counts capacity).
    entry.tables.reserve(std::size_t(
        std::count_if(active.lights.begin(), active.lights.end(), uses_table)));
    for (int k : active.lights)
        if (uses_table(k))
            entry.tables.push_back({k, tables_[k].lights, tables_[k].probability});
    // Without a table, only where the point has a slot of its own (a bake's
    // texels: the slot's bytes are spent anyway): choosing the techniques
    // again — a tree's bounds at the centre, the point's probes — was ~12 % of
    // what a later pass repeated on the race's emissive_mesh (callgrind, 64²).
    // In the map, an entry for every texel of a large map would spend the
    // budget on them.
    if (entry.tables.empty() && !kept.has_slot(point)) {
        setup.discard();  // nothing kept: not the kept tables' set-up
        return;
    }
    kept.keep(point, std::move(entry));
}

// choose_active's result from a kept entry: the same techniques in the same
// order, and each table with the CDF LightTables::make_at and make_over sums from it.
void PointLighting::Impl::restore(const TexelTables::Entry& kept, Active& active) {
    active.mask = kept.mask;
    active.light_mask = kept.light_mask;
    for (int k : p_.techniques) {
        const std::uint64_t bit = std::uint64_t(1) << k;
        if (kept.mask & bit) active.all.push_back(k);
        if (kept.light_mask & bit) active.lights.push_back(k);
    }
    for (const TexelTables::Table& t : kept.tables) {
        tables_.restore(t.technique, t.lights, t.probability);
    }
}

// The techniques of the hidden part (EstimatorPair::hidden).
void PointLighting::Impl::set_hidden_part(Active& active) const {
    active.hidden.clear();
    active.hidden_mask = 0;
    if (!p_.plan.bsdf_invisible_lights && integrand_.world_through() == ~0u) return;
    for (int k : active.all)
        if (in_hidden_part(k)) {
            active.hidden.push_back(k);
            active.hidden_mask |= std::uint64_t(1) << k;
        }
}

}  // namespace omis
