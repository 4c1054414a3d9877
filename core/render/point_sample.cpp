// One sample of one technique: its direction, its integrand and shadow, the
// densities of every active technique, added to the point's estimators.
#include "render/point_lighting_impl.h"

namespace omis {

// A sample's direction, drawn by its technique at its position p.
struct PointLighting::Impl::SampleDraw {
    Vec3 w;
    bool ok = false;
    double u1 = 0, u2 = 0;  // the shape's (or BSDF's) pair
    // A light sample's light, its light's share of the technique's density,
    // the shape's density and the distance to the point drawn on it.
    std::optional<SelectedLight> light;
    double own_density = 0, shape_pdf = 0, light_distance = 0;
};

PointLighting::Impl::SampleDraw PointLighting::Impl::draw_direction(
    const Technique& t, int k, const SurfacePoint& p, const ScrambledSobol& sequence,
    std::uint32_t index, const TableDraw& table_draw, const SelectorDraw* selected) {
    SampleDraw d;
    d.u1 = table_draw.u1, d.u2 = table_draw.u2;  // a table draw brings its light's own
    if (t.bsdf) sequence.get_2d(index, 2, d.u1, d.u2);
    sample_selection_ = {};  // none but this sample's own
    if (t.bsdf) {
        d.w = Frame(p.n).to_world(sample_cosine_hemisphere(d.u1, d.u2));
        d.ok = dot(d.w, p.n) > 0;
        return d;
    }
    if (table_draw.slot >= 0) {
        const LightTable& c = tables_[k];
        d.light = SelectedLight{c.lights[table_draw.slot], c.probability[table_draw.slot]};
    } else {
        d.light = selected->light;
        d.u1 = selected->u1;
        d.u2 = selected->u2;
        if (d.light) sample_selection_ = {selected->selector, d.light->light, d.light->pmf};
    }
    const auto s =
        d.light ? shapes_.sample(d.light->light, t.sampler, p.x, p.n, d.u1, d.u2) : std::nullopt;
    d.ok = s && s->pdf > 0 && std::isfinite(s->pdf) && isfinite(s->dir);
    if (d.ok) d.w = s->dir;
    if (d.ok) d.own_density = d.light->pmf * s->pdf, d.light_distance = s->dist;
    if (d.ok) d.shape_pdf = s->pdf;
    return d;
}

// The point's only technique draws lights: no weights to form, so a
// sample may estimate its own light's part, f_l / (P(l) p_l(ω)), which
// sums over lights to the whole integral. It needs neither the other
// lights along ω (their densities and radiance: an all-hits query, a tree
// walk each) nor a closest hit, only an occlusion ray up to the light.
// false: its density is 0 or not finite (nothing added).
bool PointLighting::Impl::add_own_light_sample(const SampleDraw& d, const SurfacePoint& p,
                                               int hidden_index, const Estimators* into,
                                               int n_into) {
    const double pdf = d.light->pmf * d.shape_pdf;
    if (!(pdf > 0 && std::isfinite(pdf))) return false;
    const Integrand::Value f = integrand_.of_light(d.light->light, p.x, p.n, p.ng, d.w);
    const double main_f[3] = {f.main.x, f.main.y, f.main.z};
    const double hidden_f[3] = {f.hidden.x, f.hidden.y, f.hidden.z};
    for (int e = 0; e < n_into; ++e) {
        into[e].main->add_sample(0, &pdf, main_f);
        if (hidden_index >= 0) into[e].hidden->add_sample(0, &pdf, hidden_f);
    }
    return true;
}

void PointLighting::Impl::take_sample(const Active& active, std::size_t a,
                                      const ScrambledSobol& sequence, std::uint32_t index,
                                      const SurfacePoint& centre, const Footprint* footprint,
                                      const Estimators* into, int n_into,
                                      const TableDraw& table_draw, const SelectorDraw* selected) {
    ++counters.samples;
    // Cancellation within a point (huge counts): see keep_going.
    if (p_.keep_going && counters.samples % 256 == 0 && !p_.keep_going())
        throw LightingCancelled{};
    // Dimension groups of the sequence: 0 footprint position, 1 the light
    // selection's bits below group 2's (a selector draws with the first
    // coordinate of group 2: draw_selector), 2 light shape or BSDF direction
    // (a light drawn from a per-point table takes its footprint position and
    // shape from its own sequence: `table_draw`).
    const int k = active.all[a];
    const Technique& t = p_.settings.techniques[k];
    // The sample's position: the centre, the selector draw's, or one drawn
    // here (referred to, not copied: two copies were ~35 instructions).
    SurfacePoint own_position;
    const SurfacePoint* at = &centre;
    if (footprint) {
        if (selected) {
            at = &selected->p;
        } else {
            double fu = table_draw.fu, fv = table_draw.fv;
            if (t.bsdf) sequence.get_2d(index, 0, fu, fv);
            own_position = footprint->at(fu, fv);
            at = &own_position;
        }
        shapes_.new_position();  // the solid-angle cache holds one position's shapes
    }
    const SurfacePoint& p = *at;
    const int hidden_index =
        into[0].hidden && in_hidden_part(k)
            ? int(std::find(active.hidden.begin(), active.hidden.end(), k) - active.hidden.begin())
            : -1;
    SampleDraw d = draw_direction(t, k, p, sequence, index, table_draw, selected);
    const bool own_light_only =
        own_light_estimates_ && active.all.size() == 1 && !t.bsdf && !pilot_;
    if (d.ok && own_light_only) {
        if (add_own_light_sample(d, p, hidden_index, into, n_into)) return;
        d.ok = false;  // a density of 0 or past the range: a null sample
    }
    // Every technique's density at the sample's own position: the position
    // density is the same for all of them, so the MIS weights are those of
    // p_k(ω | x).
    const bool split = split_parts(active);
    if (split && t.bsdf && !p_.plan.world_occluders.empty())
        return take_occluder_sample(active, p, sequence.get_1d(index, 1), d.u1, d.u2, d.w, d.ok,
                                    hidden_index, into, n_into);
    if (split && t.bsdf) return take_world_sample(active, p, d.w, d.ok, hidden_index, into, n_into);
    evaluate_and_add(active, a, p, d, hidden_index, into, n_into);
}

// A drawn direction's integrand and every technique's density there, into
// the estimators.
void PointLighting::Impl::evaluate_and_add(const Active& active, std::size_t a,
                                           const SurfacePoint& p, const SampleDraw& d,
                                           int hidden_index, const Estimators* into,
                                           int n_into) {
    const int k = active.all[a];
    const Technique& t = p_.settings.techniques[k];
    const Vec3& w = d.w;
    bool ok = d.ok;
    const bool split = split_parts(active);
    // The sample's technique in the main estimator (split: the light techniques').
    const int main_index =
        split ? int(std::find(active.lights.begin(), active.lights.end(), k) - active.lights.begin())
              : int(a);
    const std::size_t main_size = main_techniques(active).size();
    double pdfs[kMaxMisTechniques], hidden_pdfs[kMaxMisTechniques], main_pdfs[kMaxMisTechniques];
    std::optional<Integrand::Value> light_f;
    if (ok && d.light && integrand_.clips_at_blocker()) {
        light_f = integrand_.to_blocker(p.x, p.n, p.ng, w, d.light->light, d.light_distance);
        if (add_unlit_sample(main_size, main_index, hidden_index, d.own_density, *light_f, into,
                             n_into))
            return;
    } else if (ok && t.bsdf && integrand_.bsdf_to_blocker()) {
        light_f = integrand_.to_blocker(p.x, p.n, p.ng, w, ~0u, 0);
    }
    if (ok) {
        for (std::size_t b = 0; b < active.all.size(); ++b) {
            pdfs[b] = technique_pdf(active.all[b], p.x, p.n, w);
            // A light seen edge-on from x_s (a measure-zero configuration)
            // can give a non-finite density: it cannot produce ω there.
            if (!std::isfinite(pdfs[b])) pdfs[b] = 0;
        }
        ok = pdfs[a] > 0;
    }
    if (!ok) {
        if (pilot_) pilot_->add_work(k, 1.0);
        for (int e = 0; e < n_into; ++e) {
            into[e].main->add_null_sample(main_index);
            if (hidden_index >= 0) into[e].hidden->add_null_sample(hidden_index);
        }
        return;
    }
    const std::uint64_t rays_before = counters.rays;
    const Integrand::Value f = light_f ? *light_f : integrand_.at(p.x, p.n, p.ng, w);
    if (pilot_) record_sample(active, a, pdfs, f.main + f.hidden, rays_before);
    const double main_f[3] = {f.main.x, f.main.y, f.main.z};
    const double hidden_f[3] = {f.hidden.x, f.hidden.y, f.hidden.z};
    std::size_t h = 0;
    if (hidden_index >= 0)
        for (std::size_t b = 0; b < active.all.size(); ++b)
            if (in_hidden_part(active.all[b])) hidden_pdfs[h++] = pdfs[b];
    const double* own_pdfs = pdfs;
    if (split) {
        std::size_t m = 0;
        for (std::size_t b = 0; b < active.all.size(); ++b)
            if (!p_.settings.techniques[active.all[b]].bsdf) main_pdfs[m++] = pdfs[b];
        own_pdfs = main_pdfs;
    }
    for (int e = 0; e < n_into; ++e) {
        into[e].main->add_sample(main_index, own_pdfs, main_f);
        if (hidden_index >= 0) into[e].hidden->add_sample(hidden_index, hidden_pdfs, hidden_f);
    }
}

// split_parts' cosine draw: the world's part alone, seen through emitters
// (split_world) — one closest hit, no densities but its own (every
// technique of the hidden part is a `bsdf`, of one density).
void PointLighting::Impl::take_world_sample(const Active& active, const SurfacePoint& p,
                                            const Vec3& w, bool ok, int hidden_index,
                                            const Estimators* into, int n_into) {
    const double cos_theta = ok ? dot(p.n, w) : 0;
    if (!(cos_theta > 0) || hidden_index < 0) {
        for (int e = 0; e < n_into; ++e)
            if (hidden_index >= 0) into[e].hidden->add_null_sample(hidden_index);
        return;
    }
    const GeometryScene& geometry = p_.scene.geometry();
    ++counters.rays;
    const std::optional<RayHit> blocker = geometry.closest_hit(
        offset_ray_origin(p.x, p.ng, w), w, 0, std::numeric_limits<double>::infinity());
    Integrand::Value f;
    integrand_.split_world(f, p.x, w, blocker);
    const Vec3 world = f.hidden * receiver_cosine_factor(p_.settings.receiver, cos_theta);
    const double world_f[3] = {world.x, world.y, world.z};
    double pdfs[kMaxMisTechniques];
    std::fill(pdfs, pdfs + active.hidden.size(), cos_theta * kInvPi);
    for (int e = 0; e < n_into; ++e) into[e].hidden->add_sample(hidden_index, pdfs, world_f);
}

// The world's part is L_w (A − B): A = ∫_H c(ω) dω over the hemisphere,
// c the receiver's closure (receiver_cosine_factor: cos⁺/π for Lambert,
// Receiver::hemisphere_integral), B = ∫ c(ω) [the first hit along ω does not
// emit] dω. A direction whose first hit is on mesh m lies in the outline of
// m's bounding box, which from x outside the box is the union of the box
// faces turned toward x (disjoint). A face F drawn with probability W_F/W
// (W_F a positive weight, W their sum) and ω toward a point uniform on its
// area A_F (density d²/(A_F cos_F) in solid angle, d the point's distance):
//     B̂ = c(ω) (A_F cos_F / d²) W / W_F [the first hit along ω is on F's mesh],
// E[B̂] = Σ_F ∫_F c(ω)[first hit on mesh(F)] dω = B: each hidden direction
// counts once, through its own mesh's box. Unbiased; the sample enters the
// world's estimator as L_w (A − B̂) with density 1 (its only technique).
// Where x lies in a box that is not flat (its mesh may surround x) or the
// shading normal is not the geometric one (the receiver itself may then hide
// directions above n's horizon): the cosine draw w, as take_world_sample. A
// flat box holding x is a plane through x: hit at grazing only (measure
// zero), left out.
void PointLighting::Impl::take_occluder_sample(const Active& active, const SurfacePoint& p,
                                               double u_face, double u1, double u2,
                                               const Vec3& w, bool ok, int hidden_index,
                                               const Estimators* into, int n_into) {
    if (hidden_index < 0 || dot(p.n, p.ng) < 1 - 1e-9)
        return take_world_sample(active, p, w, ok, hidden_index, into, n_into);
    constexpr int kMaxFaces = 3 * kFewWorldOccluders;
    struct Face {
        Vec3 corner, edge_u, edge_v;
        std::uint32_t mesh;
    } faces[kMaxFaces];
    double weight[kMaxFaces];
    int count = 0;
    double total = 0;
    const double x[3] = {p.x.x, p.x.y, p.x.z};
    for (const EffectPlan::OccluderBox& box : p_.plan.world_occluders) {
        const double lo[3] = {box.lo.x, box.lo.y, box.lo.z}, hi[3] = {box.hi.x, box.hi.y, box.hi.z};
        bool inside = true, flat = false;
        for (int a = 0; a < 3; ++a) {
            inside = inside && lo[a] <= x[a] && x[a] <= hi[a];
            flat = flat || lo[a] == hi[a];
        }
        if (inside && flat) continue;
        if (inside) return take_world_sample(active, p, w, ok, hidden_index, into, n_into);
        for (int a = 0; a < 3; ++a) {
            if (lo[a] <= x[a] && x[a] <= hi[a]) continue;  // neither face of axis a faces x
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            if (lo[b] == hi[b] || lo[c] == hi[c]) continue;  // a face of no area
            double corner[3] = {lo[0], lo[1], lo[2]}, eu[3] = {}, ev[3] = {};
            corner[a] = x[a] < lo[a] ? lo[a] : hi[a];
            eu[b] = hi[b] - lo[b];
            ev[c] = hi[c] - lo[c];
            Face& f = faces[count];
            f = {Vec3(corner[0], corner[1], corner[2]), Vec3(eu[0], eu[1], eu[2]),
                 Vec3(ev[0], ev[1], ev[2]), box.mesh};
            // The face's solid angle about its centre (area · cos / d²): any
            // positive weight keeps B̂ unbiased; this one needs no trigonometry.
            const Vec3 d = f.corner + 0.5 * (f.edge_u + f.edge_v) - p.x;
            const double d2 = dot(d, d);
            weight[count] = eu[b] * ev[c] * std::abs(x[a] - corner[a]) / (d2 * std::sqrt(d2));
            if (!(weight[count] > 0) || !std::isfinite(weight[count])) continue;
            total += weight[count++];
        }
    }
    double hidden = 0;
    if (count > 0) {
        double pick = u_face * total;
        int f = 0;
        while (f + 1 < count && pick >= weight[f]) pick -= weight[f++];
        // A point uniform on the face's area: density d²/(A cos_F) in solid
        // angle. Against a spherical rectangle (uniform in solid angle) on
        // emission_world: 1–5 % more error per sample, 1.4× cheaper a round
        // (bench/results/error_sources.txt, 2026-12-01).
        const Face& face = faces[f];
        const Vec3 to = face.corner + u1 * face.edge_u + u2 * face.edge_v - p.x;
        const double d2 = dot(to, to);
        const Vec3 dir = to / std::sqrt(d2);
        const double cos_theta = dot(p.n, dir);
        const double cos_face = std::abs(dot(dir, normalize(cross(face.edge_u, face.edge_v))));
        if (cos_theta > 0 && cos_face > 0 && d2 > 0) {
            ++counters.rays;
            const std::optional<RayHit> blocker = p_.scene.geometry().closest_hit(
                offset_ray_origin(p.x, p.ng, dir), dir, 0, std::numeric_limits<double>::infinity());
            if (blocker && blocker->mesh == face.mesh)
                hidden = receiver_cosine_factor(p_.settings.receiver, cos_theta) *
                         length(cross(face.edge_u, face.edge_v)) * cos_face / d2 * total /
                         weight[f];
        }
    }
    const auto e = emitted_radiance(p_.scene.lights()[integrand_.world_through()], p.x, p.n);
    const Vec3 world =
        e ? e->radiance * (p_.settings.receiver.hemisphere_integral() - hidden) : Vec3();
    const double world_f[3] = {world.x, world.y, world.z};
    double pdfs[kMaxMisTechniques];
    std::fill(pdfs, pdfs + active.hidden.size(), 1.0);
    for (int e2 = 0; e2 < n_into; ++e2) into[e2].hidden->add_sample(hidden_index, pdfs, world_f);
}

// A sample whose integrand is 0 (its light hidden by a surface that does not
// emit, so that nothing along it is seen) adds 0 to every sum of the estimators,
// whatever the densities, except the optimal strategies' moments among
// several techniques (and the pilot's records). There it goes in with its
// own technique's density bounded below by its light's share (> 0) and the
// others' left at 0 — no emitter query, no tree walks.
bool PointLighting::Impl::add_unlit_sample(std::size_t main_size, int main_index,
                                           int hidden_index, double own_density,
                                           const Integrand::Value& f, const Estimators* into,
                                           int n_into) {
    const bool zero = f.main.x == 0 && f.main.y == 0 && f.main.z == 0 && f.hidden.x == 0 &&
                      f.hidden.y == 0 && f.hidden.z == 0;
    const bool densities_unused =
        !pilot_ && (main_size == 1 || !is_optimal(p_.settings.strategy));
    if (!zero || !densities_unused || !(own_density > 0) || !std::isfinite(own_density))
        return false;
    double pdfs[kMaxMisTechniques] = {}, hidden_pdfs[kMaxMisTechniques] = {};
    pdfs[main_index] = own_density;
    if (hidden_index >= 0) hidden_pdfs[hidden_index] = own_density;
    const double none[3] = {0, 0, 0};
    for (int e = 0; e < n_into; ++e) {
        into[e].main->add_sample(main_index, pdfs, none);
        if (hidden_index >= 0) into[e].hidden->add_sample(hidden_index, hidden_pdfs, none);
    }
    return true;
}

// One sample for the allocation pilot, over the settings' techniques (those
// not active here have density 0 at it). Its work: one unit for the draw, the
// densities and the integrand, and one per ray traced — a shadow ray costs
// about as much as the rest of a sample, and rays are what the techniques'
// samples differ in (a BSDF direction that meets no light traces none).
void PointLighting::Impl::record_sample(const Active& active, std::size_t a, const double* pdfs,
                                        const Vec3& f, std::uint64_t rays_before) {
    double all[kMaxMisTechniques] = {};
    for (std::size_t b = 0; b < active.all.size(); ++b) all[active.all[b]] = pdfs[b];
    const double y = luminance(f);
    pilot_->add_sample(all, &y);
    pilot_->add_work(active.all[a], 1.0 + double(counters.rays - rays_before));
}

}  // namespace omis
