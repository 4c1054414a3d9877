// The integrand along a direction: the lights seen and their radiance, the
// emitter-depth occlusion rule, the world's part behind emitters, and the
// delta lights (outside MIS).
#include "render/point_lighting_impl.h"

namespace omis {

PointLighting::Impl::Integrand PointLighting::Impl::integrand(const Vec3& x, const Vec3& n,
                                                              const Vec3& ng, const Vec3& w) {
    Integrand f;
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return f;
    hits_.clear();
    // Mesh lights whose bounding sphere w meets: the closest hit tells
    // whether their mesh is seen.
    bool meshes = false;
    for (std::uint32_t l : lights_along_.of(x, w)) {
        const Light& light = p_.scene.lights()[l];
        if (light.type == LightType::Mesh) {
            meshes = meshes || (luminance(light.emission) > 0 && mesh_light_along(light, x, w));
            continue;
        }
        const auto e = emitted_radiance(light, x, w);
        if (e && luminance(e->radiance) > 0) hits_.push_back({l, *e});
    }
    if (hits_.empty() && !meshes) return f;

    const GeometryScene& geometry = p_.scene.geometry();
    const Vec3 origin = offset_ray_origin(x, ng, w);
    // Distances below are measured from the offset origin; the offset itself
    // can exceed a relative shortening (1/65536 m near the world origin).
    const double offset = length(origin - x);
    bool need_rays = false, only_analytic = true;
    for (const Hit& h : hits_) {
        const Light& light = p_.scene.lights()[h.light];
        need_rays = need_rays || light.cast_shadow;
        only_analytic = only_analytic && light.type != LightType::Triangle;
    }
    need_rays = need_rays && p_.plan.shadow_rays;

    // One analytic light: an occlusion ray up to it. Otherwise one closest-hit
    // ray decides for every light along w, and a hit on an emitting triangle
    // (or at its depth, on a coplanar neighbour) does not shadow it.
    std::optional<RayHit> blocker;
    bool single_blocked = false;
    const bool single = hits_.size() == 1 && only_analytic && world_through_ == ~0u && !meshes;
    if (need_rays || meshes) {
        ++counters.rays;
        if (single)
            single_blocked = geometry.occluded(origin, w, 0, hits_[0].emitted.distance - offset);
        else
            blocker = geometry.closest_hit(origin, w, 0, std::numeric_limits<double>::infinity());
    }
    auto visible = [&](const Hit& h) {
        const Light& light = p_.scene.lights()[h.light];
        if (!need_rays || !light.cast_shadow) return true;
        if (single) return !single_blocked;
        if (!blocker) return true;
        const double depth = h.emitted.distance - offset;
        if (light.type != LightType::Triangle) return blocker->t >= depth;
        if (blocker->mesh == light.mesh && blocker->triangle == light.mesh_triangle) return true;
        return blocker->t >= depth * (1 - kEmitterDepthTolerance);
    };
    for (const Hit& h : hits_) {
        if (!visible(h)) continue;
        (p_.scene.lights()[h.light].visible_to_bsdf ? f.main : f.hidden) += h.emitted.radiance;
    }
    if (meshes) add_mesh_lights_seen(f, lights_along_.of(x, w), blocker);
    if (need_rays)
        split_world(f, x, w, blocker);
    // The receiver's closure (Lambert: cosθ/π), as Cycles' Diffuse bake sees it.
    const double closure = receiver_cosine_factor(p_.settings.receiver, cos_theta);
    f.main *= closure;
    f.hidden *= closure;
    return f;
}

PointLighting::Impl::Integrand PointLighting::Impl::integrand_to_blocker(
    const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& w, std::uint32_t drawn,
    double drawn_distance) {
    Integrand f;
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return f;
    const Vec3 origin = offset_ray_origin(x, ng, w);
    const double offset = length(origin - x);
    ++counters.rays;
    // The closest hit and, in one traversal, the lights along w: all of
    // them where nothing but emitters lies along w (`complete`), as a
    // light among emissive triangles is mostly seen or hidden by another.
    // Traced from the offset origin, as the closest hit: a light crossing
    // w between x and it (one touching x) is found only by lights_along().
    const GeometryScene& geometry = p_.scene.geometry();
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
                                                    &Impl::prefetch_listed, this);
    } else
        blocker = geometry.closest_hit(origin, w, 0, std::numeric_limits<double>::infinity());
    // integrand()'s rule: whether the blocker hides a light at `distance`
    // from x (a triangle is not hidden by itself, nor by a coplanar
    // neighbour at its depth).
    auto hidden = [&](const Light& light, double distance) {
        if (!blocker) return false;
        const bool triangle = light.type == LightType::Triangle;
        if (triangle && blocker->mesh == light.mesh && blocker->triangle == light.mesh_triangle)
            return false;
        return !(blocker->t >= (distance - offset) * (triangle ? 1 - kEmitterDepthTolerance : 1.0));
    };
    // The drawn light seen, or hidden by an emitting surface (a closed
    // mesh's near side): the integrand is not 0, and its densities need
    // every light along w anyway — list them all at once.
    const bool drew_light = drawn != ~0u;
    const auto& unshaped = p_.scene.unshaped_lights();
    const std::vector<std::uint32_t>* along = &clipped_;
    if (complete) {
        // Every light along w: what lights_along_.of(x, w) lists (the shapes the
        // traversal crossed, the unshaped lights, the drawn light), kept for
        // the densities (technique_pdf) as it would keep its own.
        sort_unique(merged_);
        if (!unshaped.empty()) merged_.insert(merged_.end(), unshaped.begin(), unshaped.end());
        if (drew_light) add_if_missing(merged_, drawn);
        along = &lights_along_.adopt(x, w, merged_);
    } else if (!blocker && shapes_in_geometry_) {
        // Nothing hit: no emissive triangle lies along w (but the drawn one,
        // where single precision missed its edge), only the unshaped lights.
        clipped_.assign(unshaped.begin(), unshaped.end());
        if (drew_light) add_if_missing(clipped_, drawn);
    } else if (drew_light ? !hidden(p_.scene.lights()[drawn], drawn_distance) ||
                                p_.scene.geometry().mesh(blocker->mesh).is_emissive()
                          : !blocker || p_.scene.geometry().mesh(blocker->mesh).is_emissive()) {
        along = &lights_along_.of(x, w);
    } else {
        // Hidden: no light past the blocker is seen, at most
        // blocker->t / (1 − tolerance) + offset from x. The emitter shapes'
        // distances are single precision: a margin far above their rounding
        // (relative to the coordinates' size) keeps every such light listed.
        const double reach = blocker->t / (1 - kEmitterDepthTolerance) + offset;
        const double scale = std::max({std::abs(x.x), std::abs(x.y), std::abs(x.z), reach});
        clipped_.clear();
        p_.scene.emitter_shapes().lights_along(x, w, clipped_, reach * (1 + 1e-4) + 1e-5 * scale);
        // Unshaped lights (a world, a sun's disk, a point light's) are listed
        // by no shape: `hidden` below judges them by their distance.
        clipped_.insert(clipped_.end(), unshaped.begin(), unshaped.end());
        // As lights_along(): the drawn light surely lies along w.
        if (drew_light) add_if_missing(clipped_, drawn);
    }
    // The triangles' hit tests kept for their densities (Along::tests).
    TriangleTest* tests = lights_along_.is_list(along) ? lights_along_.begin_tests() : nullptr;
    for (std::size_t i = 0; i < along->size(); ++i) {
        const Light& light = p_.scene.lights()[(*along)[i]];
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
    const double closure = receiver_cosine_factor(p_.settings.receiver, cos_theta);
    f.main *= closure;
    f.hidden *= closure;
    return f;
}

PointLighting::Impl::Integrand PointLighting::Impl::light_integrand(std::uint32_t l,
                                                                    const Vec3& x,
                                                                    const Vec3& n,
                                                                    const Vec3& ng,
                                                                    const Vec3& w) {
    Integrand f;
    const auto u = light_unoccluded(l, x, n, w);
    if (!u || light_occluded(l, x, ng, w, u->distance)) return f;
    (p_.scene.lights()[l].visible_to_bsdf ? f.main : f.hidden) = u->radiance * u->cosine_factor;
    return f;
}

std::optional<PointLighting::Impl::Unoccluded> PointLighting::Impl::light_unoccluded(
    std::uint32_t l, const Vec3& x, const Vec3& n, const Vec3& w) const {
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return std::nullopt;
    const Light& light = p_.scene.lights()[l];
    if (light.type == LightType::Mesh) {
        // Its emission wherever w may meet its mesh: light_occluded then
        // tells whether the closest hit is on it.
        if (!mesh_light_along(light, x, w) || !(luminance(light.emission) > 0)) return std::nullopt;
        return Unoccluded{light.emission, receiver_cosine_factor(p_.settings.receiver, cos_theta),
                          std::numeric_limits<double>::infinity()};
    }
    const auto e = emitted_radiance(light, x, w);
    if (!e || !(luminance(e->radiance) > 0)) return std::nullopt;
    return Unoccluded{e->radiance, receiver_cosine_factor(p_.settings.receiver, cos_theta),
                      e->distance};
}

bool PointLighting::Impl::light_occluded(std::uint32_t l, const Vec3& x, const Vec3& ng,
                                         const Vec3& w, double distance) {
    const Light& light = p_.scene.lights()[l];
    if (light.type == LightType::Mesh) {
        // Seen where the closest hit is on its mesh (its mesh is the
        // emitter: a ray is traced whatever the plan says of shadows).
        ++counters.rays;
        const auto hit = p_.scene.geometry().closest_hit(offset_ray_origin(x, ng, w), w, 0,
                                                         std::numeric_limits<double>::infinity());
        return !hit || hit->mesh != light.mesh;
    }
    if (!p_.plan.shadow_rays || !light.cast_shadow) return false;
    // Up to the emitting point; a triangle's own surface (or a coplanar
    // neighbour at its depth) does not shadow it, as in integrand().
    const Vec3 origin = offset_ray_origin(x, ng, w);
    double depth = distance - length(origin - x);
    if (light.type == LightType::Triangle) depth *= 1 - kEmitterDepthTolerance;
    ++counters.rays;
    return p_.scene.geometry().occluded(origin, w, 0, depth);
}

// Delta lights are not integrated: one shadow ray each when they are few; when
// they are many (plan.sample_delta_lights), their sum is estimated by drawing
// delta_samples lights from the light tree, u rotated over [0, 1) for each,
// weighted by 1/pmf — unbiased, as Cycles does.
Vec3 PointLighting::Impl::delta_lighting(const SurfacePoint& p, double u) {
    auto contribution = [&](std::uint32_t l) {
        const Light& light = p_.scene.lights()[l];
        const auto d = delta_illumination(light, p.x, p.n);
        if (!d) return Vec3();
        if (light.cast_shadow && p_.plan.shadow_rays) {
            ++counters.rays;
            if (p_.scene.geometry().occluded(offset_ray_origin(p.x, p.ng, d->direction),
                                             d->direction, 0, d->distance))
                return Vec3();
        }
        // E/π for Lambert; other receivers scale it by their closure's ratio.
        return d->irradiance *
               (kInvPi * p_.settings.receiver.lambert_ratio(dot(p.n, d->direction)));
    };
    Vec3 total;
    if (!p_.plan.sample_delta_lights) {
        for (std::uint32_t l : p_.delta) total += contribution(l);
        return total;
    }
    const int draws = p_.plan.delta_samples;
    for (int j = 0; j < draws; ++j) {
        const double uj = u + double(j) / draws;
        const auto pick =
            p_.delta_selector->sample(p.x, p.n, uj - std::floor(uj), &delta_memo_);
        if (pick) total += contribution(pick->light) / pick->pmf;
    }
    return total / double(draws);
}

}  // namespace omis
