// The integrand along a direction: the lights seen and their radiance, the
// emitter-depth occlusion rule, the world's part behind emitters, and the
// delta lights (outside MIS).
#include "render/integrand.h"

#include "render/point_lighting_impl.h"

namespace omis {

Integrand::Integrand(const LightingContext& context, LightsAlong& along,
                     LightingCounters& counters)
    : context_(context),
      along_(along),
      counters_(counters),
      clip_at_blocker_(context.settings.fast_paths && context.plan.shadow_rays &&
                       std::all_of(context.scene.lights().begin(), context.scene.lights().end(),
                                   [](const Light& l) { return l.cast_shadow; }) &&
                       std::any_of(context.scene.lights().begin(), context.scene.lights().end(),
                                   [](const Light& l) { return l.type == LightType::Triangle; })),
      world_light_([&] {
          for (std::uint32_t l = 0; l < context.scene.lights().size(); ++l)
              if (context.scene.lights()[l].type == LightType::World) return l;
          return ~0u;
      }()),
      bsdf_to_blocker_(clip_at_blocker_ && world_light_ != ~0u),
      world_through_(context.plan.world_through_emitters ? world_light_ : ~0u),
      shapes_in_geometry_(std::all_of(
          context.scene.lights().begin(), context.scene.lights().end(), [&](const Light& l) {
              const auto& unshaped = context.scene.unshaped_lights();
              return l.is_delta() || l.type == LightType::Triangle ||
                     std::find(unshaped.begin(), unshaped.end(),
                               std::uint32_t(&l - context.scene.lights().data())) !=
                         unshaped.end();
          })) {}

void Integrand::add_mesh_lights_seen(Value& f, const std::vector<std::uint32_t>& lights,
                                     const std::optional<RayHit>& blocker) const {
    if (!blocker || !context_.scene.geometry().mesh(blocker->mesh).is_emissive()) return;
    for (std::uint32_t l : lights) {
        const Light& light = context_.scene.lights()[l];
        if (light.type == LightType::Mesh && light.mesh == blocker->mesh)
            (light.visible_to_bsdf ? f.main : f.hidden) += light.emission;
    }
}

void Integrand::scale_by_closure(Value& f, double cos_theta) const {
    const double closure = receiver_cosine_factor(context_.settings.receiver, cos_theta);
    f.main *= closure;
    f.hidden *= closure;
}

void Integrand::prefetch_listed(void* self, std::uint32_t l) {
    const LightingContext& context = static_cast<const Integrand*>(self)->context_;
    prefetch_record(&context.scene.lights()[l]);
    if (context.tree_selector) context.tree_selector->prefetch(l);
}

Integrand::Value Integrand::at(const Vec3& x, const Vec3& n,
                                                              const Vec3& ng, const Vec3& w) {
    Value f;
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return f;
    hits_.clear();
    // Mesh lights whose bounding sphere w meets: the closest hit tells
    // whether their mesh is seen.
    bool meshes = false;
    for (std::uint32_t l : along_.of(x, w)) {
        const Light& light = context_.scene.lights()[l];
        if (light.type == LightType::Mesh) {
            meshes = meshes || (luminance(light.emission) > 0 && mesh_light_along(light, x, w));
            continue;
        }
        const auto e = emitted_radiance(light, x, w);
        if (e && luminance(e->radiance) > 0) hits_.push_back({l, *e});
    }
    if (hits_.empty() && !meshes) return f;

    const GeometryScene& geometry = context_.scene.geometry();
    const Vec3 origin = offset_ray_origin(x, ng, w);
    // Distances below are measured from the offset origin; the offset itself
    // can exceed a relative shortening (1/65536 m near the world origin).
    const double offset = length(origin - x);
    bool need_rays = false, only_analytic = true;
    for (const Hit& h : hits_) {
        const Light& light = context_.scene.lights()[h.light];
        need_rays = need_rays || light.cast_shadow;
        only_analytic = only_analytic && light.type != LightType::Triangle;
    }
    need_rays = need_rays && context_.plan.shadow_rays;

    // One analytic light: an occlusion ray up to it. Otherwise one closest-hit
    // ray decides for every light along w, and a hit on an emitting triangle
    // (or at its depth, on a coplanar neighbour) does not shadow it.
    std::optional<RayHit> blocker;
    bool single_blocked = false;
    const bool single = hits_.size() == 1 && only_analytic && world_through_ == ~0u && !meshes;
    if (need_rays || meshes) {
        ++counters_.rays;
        if (single)
            single_blocked = geometry.occluded(origin, w, 0, hits_[0].emitted.distance - offset);
        else
            blocker = geometry.closest_hit(origin, w, 0, std::numeric_limits<double>::infinity());
    }
    auto visible = [&](const Hit& h) {
        const Light& light = context_.scene.lights()[h.light];
        if (!need_rays || !light.cast_shadow) return true;
        if (single) return !single_blocked;
        return !blocker || !hides(*blocker, light, h.emitted.distance - offset);
    };
    for (const Hit& h : hits_) {
        if (!visible(h)) continue;
        (context_.scene.lights()[h.light].visible_to_bsdf ? f.main : f.hidden) += h.emitted.radiance;
    }
    if (meshes) add_mesh_lights_seen(f, along_.of(x, w), blocker);
    if (need_rays)
        split_world(f, x, w, blocker);
    scale_by_closure(f, cos_theta);
    return f;
}

// to_blocker's lights along w, from its closest hit `blocker` (`complete`:
// the traversal listed every light along w in merged_).
const std::vector<std::uint32_t>& Integrand::lights_to_blocker(
    const Vec3& x, const Vec3& w, const std::optional<RayHit>& blocker, bool complete,
    double offset, std::uint32_t sampled_light, double sampled_distance) {
    // Whether the blocker hides the sampled light (the one rule: hides).
    auto hidden = [&](const Light& light) {
        return blocker && hides(*blocker, light, sampled_distance - offset);
    };
    // The drawn light seen, or hidden by an emitting surface (a closed
    // mesh's near side): the integrand is not 0, and its densities need
    // every light along w anyway — list them all at once.
    const bool sampled = sampled_light != ~0u;
    const auto& unshaped = context_.scene.unshaped_lights();
    if (complete) {
        // Every light along w: what along_.of(x, w) lists (the shapes the
        // traversal crossed, the unshaped lights, the drawn light), kept for
        // the densities (technique_pdf) as it would keep its own.
        sort_unique(merged_);
        if (!unshaped.empty()) merged_.insert(merged_.end(), unshaped.begin(), unshaped.end());
        if (sampled) add_if_missing(merged_, sampled_light);
        return along_.adopt(x, w, merged_);
    } else if (!blocker && shapes_in_geometry_) {
        // Nothing hit: no emissive triangle lies along w (but the drawn one,
        // where single precision missed its edge), only the unshaped lights.
        clipped_.assign(unshaped.begin(), unshaped.end());
        if (sampled) add_if_missing(clipped_, sampled_light);
    } else if (sampled ? !hidden(context_.scene.lights()[sampled_light]) ||
                                context_.scene.geometry().mesh(blocker->mesh).is_emissive()
                          : !blocker || context_.scene.geometry().mesh(blocker->mesh).is_emissive()) {
        return along_.of(x, w);
    } else {
        // Hidden: no light past the blocker is seen, at most
        // blocker->t / (1 − tolerance) + offset from x. The emitter shapes'
        // distances are single precision: a margin far above their rounding
        // (relative to the coordinates' size) keeps every such light listed.
        const double reach = blocker->t / (1 - kEmitterDepthTolerance) + offset;
        const double scale = std::max({std::abs(x.x), std::abs(x.y), std::abs(x.z), reach});
        clipped_.clear();
        context_.scene.emitter_shapes().lights_along(x, w, clipped_, reach * (1 + 1e-4) + 1e-5 * scale);
        // Unshaped lights (a world, a sun's disk, a point light's) are listed
        // by no shape: to_blocker judges them by their distance.
        clipped_.insert(clipped_.end(), unshaped.begin(), unshaped.end());
        // As lights_along(): the drawn light surely lies along w.
        if (sampled) add_if_missing(clipped_, sampled_light);
    }
    return clipped_;
}

Integrand::Value Integrand::to_blocker(
    const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& w, std::uint32_t sampled_light,
    double sampled_distance) {
    Value f;
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return f;
    const Vec3 origin = offset_ray_origin(x, ng, w);
    const double offset = length(origin - x);
    ++counters_.rays;
    // The closest hit and, in one traversal, the lights along w: all of
    // them where nothing but emitters lies along w (`complete`), as a
    // light among emissive triangles is mostly seen or hidden by another.
    // Traced from the offset origin, as the closest hit: a light crossing
    // w between x and it (one touching x) is found only by lights_along().
    const GeometryScene& geometry = context_.scene.geometry();
    bool complete = false;
    std::optional<RayHit> blocker;
    merged_.clear();
    if (geometry.has_emitter_candidates()) {
        // The lights found are read next (their radiance, then their
        // shapes' densities and tree pmfs): among 100k lights each record is
        // a cache miss, started as the traversal lists the light (the far
        // side of a closed mesh is still to be traversed) instead of one
        // after another once it is done.
        blocker = geometry.closest_hit_and_emitters(origin, w, merged_, complete,
                                                    &Integrand::prefetch_listed, this);
    } else
        blocker = geometry.closest_hit(origin, w, 0, std::numeric_limits<double>::infinity());
    // Whether the blocker hides a light at `distance` from x (the one rule: hides).
    auto hidden = [&](const Light& light, double distance) {
        return blocker && hides(*blocker, light, distance - offset);
    };
    const std::vector<std::uint32_t>& along_w =
        lights_to_blocker(x, w, blocker, complete, offset, sampled_light, sampled_distance);
    const std::vector<std::uint32_t>* along = &along_w;
    // The triangles' hit tests kept for their densities (Along::tests).
    TriangleTest* tests = along_.is_list(along) ? along_.begin_tests() : nullptr;
    for (std::size_t i = 0; i < along->size(); ++i) {
        const Light& light = context_.scene.lights()[(*along)[i]];
        std::optional<Emitted> e;
        if (light.type == LightType::Mesh) {
            if (tests) tests[i].known = false;
            continue;  // below, from the blocker
        }
        if (light.type == LightType::Triangle) {
            // Hidden first: the triangles behind the blocker (a closed mesh's
            // far side, about one a sample) need no radiance.
            const auto hit = light.triangle.intersect(x, w);
            if (tests) tests[i] = {true, hit};
            if (!hit || hidden(light, hit->t)) continue;
            e = triangle_emitted(light, w, hit->t);
        } else {
            if (tests) tests[i].known = false;
            e = emitted_radiance(light, x, w);
        }
        if (!e || !(luminance(e->radiance) > 0) || hidden(light, e->distance)) continue;
        (light.visible_to_bsdf ? f.main : f.hidden) += e->radiance;
    }
    add_mesh_lights_seen(f, *along, blocker);
    split_world(f, x, w, blocker);
    scale_by_closure(f, cos_theta);
    return f;
}

Integrand::Value Integrand::of_light(std::uint32_t l,
                                                                    const Vec3& x,
                                                                    const Vec3& n,
                                                                    const Vec3& ng,
                                                                    const Vec3& w) {
    Value f;
    const auto u = unoccluded(l, x, n, w);
    if (!u || occluded(l, x, ng, w, u->distance)) return f;
    (context_.scene.lights()[l].visible_to_bsdf ? f.main : f.hidden) = u->radiance * u->cosine_factor;
    return f;
}

std::optional<Integrand::Unoccluded> Integrand::unoccluded(
    std::uint32_t l, const Vec3& x, const Vec3& n, const Vec3& w) const {
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return std::nullopt;
    const Light& light = context_.scene.lights()[l];
    if (light.type == LightType::Mesh) {
        // Its emission wherever w may meet its mesh: light_occluded then
        // tells whether the closest hit is on it.
        if (!mesh_light_along(light, x, w) || !(luminance(light.emission) > 0)) return std::nullopt;
        return Unoccluded{light.emission, receiver_cosine_factor(context_.settings.receiver, cos_theta),
                          std::numeric_limits<double>::infinity()};
    }
    const auto e = emitted_radiance(light, x, w);
    if (!e || !(luminance(e->radiance) > 0)) return std::nullopt;
    return Unoccluded{e->radiance, receiver_cosine_factor(context_.settings.receiver, cos_theta),
                      e->distance};
}

bool Integrand::occluded(std::uint32_t l, const Vec3& x, const Vec3& ng,
                                         const Vec3& w, double distance) {
    const Light& light = context_.scene.lights()[l];
    if (light.type == LightType::Mesh) {
        // Seen where the closest hit is on its mesh (its mesh is the
        // emitter: a ray is traced whatever the plan says of shadows).
        ++counters_.rays;
        const auto hit = context_.scene.geometry().closest_hit(offset_ray_origin(x, ng, w), w, 0,
                                                         std::numeric_limits<double>::infinity());
        return !hit || hit->mesh != light.mesh;
    }
    if (!context_.plan.shadow_rays || !light.cast_shadow) return false;
    // Up to the emitting point; a triangle's own surface (or a coplanar
    // neighbour at its depth) does not shadow it (shadow_depth).
    const Vec3 origin = offset_ray_origin(x, ng, w);
    const double depth = shadow_depth(light, distance - length(origin - x));
    ++counters_.rays;
    return context_.scene.geometry().occluded(origin, w, 0, depth);
}

// Delta lights are not integrated: one shadow ray each when they are few; when
// they are many (plan.sample_delta_lights), their sum is estimated by drawing
// delta_samples lights from the light tree, u rotated over [0, 1) for each,
// weighted by 1/pmf — unbiased, as Cycles does.
Vec3 Integrand::delta_lighting(const SurfacePoint& p, double u) {
    auto contribution = [&](std::uint32_t l) {
        const Light& light = context_.scene.lights()[l];
        const auto d = delta_illumination(light, p.x, p.n);
        if (!d) return Vec3();
        if (light.cast_shadow && context_.plan.shadow_rays) {
            ++counters_.rays;
            if (context_.scene.geometry().occluded(offset_ray_origin(p.x, p.ng, d->direction),
                                             d->direction, 0, d->distance))
                return Vec3();
        }
        // E/π for Lambert; other receivers scale it by their closure's ratio.
        return d->irradiance *
               (kInvPi * context_.settings.receiver.lambert_ratio(dot(p.n, d->direction)));
    };
    Vec3 total;
    if (!context_.plan.sample_delta_lights) {
        for (std::uint32_t l : context_.delta) total += contribution(l);
        return total;
    }
    const int draws = context_.plan.delta_samples;
    for (int j = 0; j < draws; ++j) {
        const double uj = u + double(j) / draws;
        const auto pick =
            context_.delta_selector->sample(p.x, p.n, uj - std::floor(uj), &delta_memo_);
        if (pick) total += contribution(pick->light) / pick->pmf;
    }
    return total / double(draws);
}

}  // namespace omis
