#include "render/direct_lighting.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "math/random.h"
#include "mis/estimator.h"
#include "sampling/spherical.h"
#include "sampling/warp.h"
#include "scene/ray_offset.h"

namespace omis {
namespace {

// An emissive triangle is geometry too: a closest hit within this relative
// depth of it is the emitter itself or a coplanar neighbour, not a blocker.
constexpr double kEmitterDepthTolerance = 1e-4;

// A light technique at one point: the lights it may pick and their CDF.
struct LightChoice {
    std::vector<std::uint32_t> lights;
    std::vector<double> probability, cdf;
};

}  // namespace

struct PointLighting::Impl {
    Impl(const LightingContext& context, LightingCounters& counters)
        : p_(context), counters(counters), choices_(context.settings.techniques.size()) {}

    void shade(std::uint64_t stream, int first_round, int rounds, const Vec3& x, const Vec3& n,
               const Vec3& ng, double* value, double* variance);

    struct Integrand {
        Vec3 main, hidden;  // lights BSDF rays see, and those they do not
    };
    Integrand integrand(const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& w);
    double technique_pdf(int k, const Vec3& x, const Vec3& n, const Vec3& w);
    void choose_lights(int k, const Vec3& x, const Vec3& n);
    MisEstimator& estimator(std::unordered_map<std::uint64_t, MisEstimator>& cache,
                            std::uint64_t mask, const std::vector<int>& active);

    // Spherical rectangles/triangles depend on the point only: build each once
    // per point instead of once per sample and pdf evaluation. (Skipped for
    // scenes with very many lights, where the table would not pay.)
    struct SolidAngleCache {
        std::uint64_t point = ~0ull;
        std::optional<SphericalRect> rect;
        std::optional<SphericalTriangle> triangle;
    };
    static constexpr std::size_t kMaxCachedLights = 1024;
    const SolidAngleCache* solid_angle(std::uint32_t l, const Vec3& x);
    std::optional<LightSample> sample(std::uint32_t l, LightSampler sampler, const Vec3& x,
                                      const Vec3& n, double u1, double u2);
    double pdf(std::uint32_t l, LightSampler sampler, const Vec3& x, const Vec3& n,
               const Vec3& w);
    std::vector<SolidAngleCache> solid_angle_cache_;
    std::uint64_t point_serial_ = 0;

    const LightingContext& p_;
    LightingCounters& counters;
    std::vector<LightChoice> choices_;  // per technique (light techniques only)
    std::unordered_map<std::uint64_t, MisEstimator> main_cache_, hidden_cache_;
    struct Hit {
        std::uint32_t light;
        Emitted emitted;
    };
    std::vector<Hit> hits_;
};

const PointLighting::Impl::SolidAngleCache* PointLighting::Impl::solid_angle(std::uint32_t l,
                                                                             const Vec3& x) {
    const Light& light = p_.scene.lights()[l];
    if (light.type != LightType::Rect && light.type != LightType::Triangle) return nullptr;
    if (p_.scene.lights().size() > kMaxCachedLights) return nullptr;
    if (solid_angle_cache_.size() != p_.scene.lights().size())
        solid_angle_cache_.resize(p_.scene.lights().size());
    SolidAngleCache& c = solid_angle_cache_[l];
    if (c.point != point_serial_) {
        c.point = point_serial_;
        if (light.type == LightType::Rect)
            c.rect = SphericalRect::make(x, light.rect.corner, light.rect.edge_u, light.rect.edge_v);
        else
            c.triangle = SphericalTriangle::make(x, light.triangle.p0, light.triangle.p1,
                                                 light.triangle.p2);
    }
    return &c;
}

std::optional<LightSample> PointLighting::Impl::sample(std::uint32_t l, LightSampler sampler,
                                                       const Vec3& x, const Vec3& n, double u1,
                                                       double u2) {
    const SolidAngleCache* c =
        sampler == LightSampler::SolidAngle ? solid_angle(l, x) : nullptr;
    if (!c) return sample_light(p_.scene.lights()[l], sampler, x, n, u1, u2);
    // The same draw as RectLight/TriangleLight::sample_solid_angle, from the cache.
    if (c->rect) {
        const DirSample s = c->rect->sample(u1, u2);
        return LightSample{s.dir, s.dist, 1.0 / c->rect->solid_angle()};
    }
    if (c->triangle) {
        const DirSample s = c->triangle->sample(u1, u2);
        return LightSample{s.dir, s.dist, 1.0 / c->triangle->solid_angle()};
    }
    return std::nullopt;
}

double PointLighting::Impl::pdf(std::uint32_t l, LightSampler sampler, const Vec3& x,
                                const Vec3& n, const Vec3& w) {
    const SolidAngleCache* c =
        sampler == LightSampler::SolidAngle ? solid_angle(l, x) : nullptr;
    if (!c) return light_pdf(p_.scene.lights()[l], sampler, x, n, w);
    if (c->rect) return c->rect->pdf(w);
    if (c->triangle) return c->triangle->pdf(w);
    return 0.0;
}

void PointLighting::Impl::choose_lights(int k, const Vec3& x, const Vec3& n) {
    const Technique& t = p_.settings.techniques[k];
    LightChoice& c = choices_[k];
    c.lights.clear();
    c.probability.clear();
    c.cdf.clear();
    double total = 0, largest = 0;
    for (std::uint32_t l : p_.integrated) {
        const Light& light = p_.scene.lights()[l];
        if (!sampler_applies(light, t.sampler, x, n)) continue;
        double w = 1.0;
        if (t.selection == LightSelection::Power) w = p_.power[l];
        if (t.selection == LightSelection::Unoccluded) w = unoccluded_irradiance(light, x, n);
        c.lights.push_back(l);
        c.probability.push_back(w);
        largest = std::max(largest, w);
    }
    // A light that reaches x but whose weight rounds to zero keeps a tiny share,
    // so every direction the integrand covers stays sampleable.
    for (double& w : c.probability) {
        if (!(w > 0)) w = largest > 0 ? 1e-9 * largest : 1.0;
        total += w;
    }
    double running = 0;
    for (double& w : c.probability) {
        w /= total;
        running += w;
        c.cdf.push_back(running);
    }
    if (!c.cdf.empty()) c.cdf.back() = 1.0;
}

PointLighting::Impl::Integrand PointLighting::Impl::integrand(const Vec3& x, const Vec3& n,
                                                              const Vec3& ng, const Vec3& w) {
    Integrand f;
    const double cos_theta = dot(n, w);
    if (!(cos_theta > 0)) return f;
    hits_.clear();
    for (std::uint32_t l : p_.integrated) {
        const auto e = emitted_radiance(p_.scene.lights()[l], x, w);
        if (e && luminance(e->radiance) > 0) hits_.push_back({l, *e});
    }
    if (hits_.empty()) return f;

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
    std::optional<omis::Hit> blocker;
    bool single_blocked = false;
    const bool single = hits_.size() == 1 && only_analytic;
    if (need_rays) {
        ++counters.rays;
        if (single)
            single_blocked = geometry.occluded(origin, w, 0, hits_[0].emitted.distance - offset);
        else
            blocker = geometry.intersect(origin, w, 0, std::numeric_limits<double>::infinity());
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
    f.main *= cos_theta * kInvPi;
    f.hidden *= cos_theta * kInvPi;
    return f;
}

double PointLighting::Impl::technique_pdf(int k, const Vec3& x, const Vec3& n, const Vec3& w) {
    const Technique& t = p_.settings.techniques[k];
    if (t.bsdf) return std::max(0.0, dot(n, w)) * kInvPi;
    const LightChoice& c = choices_[k];
    double pdf = 0;
    for (std::size_t i = 0; i < c.lights.size(); ++i)
        pdf += c.probability[i] * this->pdf(c.lights[i], t.sampler, x, n, w);
    counters.pdf_evaluations += c.lights.size();
    return pdf;
}

MisEstimator& PointLighting::Impl::estimator(std::unordered_map<std::uint64_t, MisEstimator>& cache,
                                     std::uint64_t mask, const std::vector<int>& active) {
    auto it = cache.find(mask);
    if (it == cache.end()) {
        std::vector<int> counts;
        for (int k : active) counts.push_back(p_.settings.samples[k]);
        it = cache.emplace(mask, MisEstimator(p_.settings.strategy, int(active.size()), 3,
                                              counts, p_.settings.options))
                 .first;
    }
    it->second.reset();
    ++counters.systems;
    return it->second;
}

void PointLighting::Impl::shade(std::uint64_t stream, int first_round, int rounds,
                                const Vec3& x, const Vec3& n, const Vec3& ng, double* value,
                                double* variance) {
    Vec3 total, total_variance;
    const GeometryScene& geometry = p_.scene.geometry();
    ++point_serial_;  // invalidates the per-point solid-angle cache

    // Delta lights: one deterministic shadow ray each.
    for (std::uint32_t l : p_.delta) {
        const Light& light = p_.scene.lights()[l];
        const auto d = delta_illumination(light, x, n);
        if (!d) continue;
        if (light.cast_shadow && p_.plan.shadow_rays) {
            ++counters.rays;
            if (geometry.occluded(offset_ray_origin(x, ng, d->direction), d->direction, 0,
                                  d->distance))
                continue;
        }
        total += d->irradiance * kInvPi;
    }

    // Which enabled techniques apply here: a light technique needs a light its
    // sampler can reach from this point.
    std::vector<int> active, active_lights;
    std::uint64_t mask = 0, light_mask = 0;
    for (int k : p_.techniques) {
        const Technique& t = p_.settings.techniques[k];
        if (!t.bsdf) {
            choose_lights(k, x, n);
            if (choices_[k].lights.empty()) continue;
            active_lights.push_back(k);
            light_mask |= std::uint64_t(1) << k;
        }
        active.push_back(k);
        mask |= std::uint64_t(1) << k;
    }

    if (!active.empty()) {
        MisEstimator& est = estimator(main_cache_, mask, active);
        const bool hidden = p_.plan.bsdf_invisible_lights && !active_lights.empty();
        MisEstimator* hidden_est = hidden ? &estimator(hidden_cache_, light_mask, active_lights)
                                          : nullptr;
        Pcg32 rng = point_stream(p_.settings.seed, stream);
        const Frame frame(n);
        double pdfs[kMaxMisTechniques], hidden_pdfs[kMaxMisTechniques];
        // Each technique's draws at this point follow a randomly shifted R3
        // sequence (Roberts 2018; Cranley–Patterson rotation): every draw is
        // still uniform, so estimates stay unbiased, but the draws of one point
        // spread evenly over the light and the hemisphere instead of
        // clustering. Variance estimates, derived as for independent draws,
        // become conservative.
        double shift[kMaxMisTechniques][3];
        for (std::size_t a = 0; a < active.size(); ++a)
            for (double& s : shift[a]) s = rng.next_double();
        auto draw = [&](std::size_t a, int index, int dim) {
            static constexpr double kR3[3] = {0.8191725133961645, 0.6710436067037893,
                                              0.5497004779019703};
            const double u = shift[a][dim] + index * kR3[dim];
            return u - std::floor(u);
        };

        for (int r = first_round; r < first_round + rounds; ++r) {
            for (std::size_t a = 0; a < active.size(); ++a) {
                const int k = active[a];
                const Technique& t = p_.settings.techniques[k];
                const int hidden_index = hidden && !t.bsdf
                    ? int(std::find(active_lights.begin(), active_lights.end(), k) - active_lights.begin())
                    : -1;
                for (int j = 0; j < p_.settings.samples[k]; ++j) {
                    ++counters.samples;
                    // Cancellation within a point (huge counts): see keep_going.
                    if (p_.keep_going && counters.samples % 256 == 0 && !p_.keep_going())
                        throw LightingCancelled{};
                    const int index = r * p_.settings.samples[k] + j;
                    const double u0 = draw(a, index, 0), u1 = draw(a, index, 1),
                                 u2 = draw(a, index, 2);
                    Vec3 w;
                    bool ok;
                    if (t.bsdf) {
                        w = frame.to_world(sample_cosine_hemisphere(u1, u2));
                        ok = dot(w, n) > 0;
                    } else {
                        const LightChoice& c = choices_[k];
                        const std::size_t i = std::min<std::size_t>(
                            std::upper_bound(c.cdf.begin(), c.cdf.end(), u0) - c.cdf.begin(),
                            c.lights.size() - 1);
                        const auto s = sample(c.lights[i], t.sampler, x, n, u1, u2);
                        ok = s && s->pdf > 0 && std::isfinite(s->pdf) && isfinite(s->dir);
                        if (ok) w = s->dir;
                    }
                    if (ok) {
                        for (std::size_t b = 0; b < active.size(); ++b)
                            pdfs[b] = technique_pdf(active[b], x, n, w);
                        ok = pdfs[a] > 0 && std::isfinite(pdfs[a]);
                    }
                    if (!ok) {
                        est.add_null_sample(int(a));
                        if (hidden_index >= 0) hidden_est->add_null_sample(hidden_index);
                        continue;
                    }
                    const Integrand f = integrand(x, n, ng, w);
                    const double main_f[3] = {f.main.x, f.main.y, f.main.z};
                    est.add_sample(int(a), pdfs, main_f);
                    if (hidden_index >= 0) {
                        std::size_t h = 0;
                        for (std::size_t b = 0; b < active.size(); ++b)
                            if (!p_.settings.techniques[active[b]].bsdf) hidden_pdfs[h++] = pdfs[b];
                        const double hidden_f[3] = {f.hidden.x, f.hidden.y, f.hidden.z};
                        hidden_est->add_sample(hidden_index, hidden_pdfs, hidden_f);
                    }
                }
            }
        }
        for (MisEstimator* e : {&est, hidden_est}) {
            if (!e) continue;
            const MisResult result = e->result();
            total += Vec3(result.estimate[0], result.estimate[1], result.estimate[2]);
            total_variance +=
                Vec3(result.variance[0], result.variance[1], result.variance[2]);
        }
    }
    for (int c = 0; c < 3; ++c) {
        value[c] = total[c];
        variance[c] = total_variance[c];
    }
}

namespace {

void validate(const Scene& scene, const DirectLightingSettings& s) {
    if (!scene.committed())
        throw std::logic_error("scene: not committed (call commit before lighting)");
    if (s.techniques.size() != s.samples.size())
        throw std::invalid_argument("samples: expected one count per technique (" +
                                    std::to_string(s.techniques.size()) + "), got " +
                                    std::to_string(s.samples.size()));
    if (s.techniques.size() > kMaxMisTechniques)
        throw std::invalid_argument("techniques: at most 32");
    for (int n : s.samples)
        if (n < 0) throw std::invalid_argument("samples: counts must not be negative");
    if (s.rounds < 1) throw std::invalid_argument("rounds: must be at least 1");
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
}

}  // namespace

LightingContext::LightingContext(const Scene& scene_, const DirectLightingSettings& s)
    : scene((validate(scene_, s), scene_)),
      settings(s),
      plan(plan_effects(scene_, s.techniques, s.samples)) {
    for (std::size_t k = 0; k < settings.techniques.size(); ++k)
        if (plan.enabled[k]) techniques.push_back(int(k));
    for (std::uint32_t l = 0; l < scene.lights().size(); ++l) {
        const Light& light = scene.lights()[l];
        (light.is_delta() ? delta : integrated).push_back(l);
        power.push_back(light.power(scene.bounding_radius()));
    }
}

PointLighting::PointLighting(const LightingContext& context)
    : impl_(std::make_unique<Impl>(context, counters)) {}
PointLighting::~PointLighting() = default;
PointLighting::PointLighting(PointLighting&& other) noexcept
    : counters(other.counters), impl_(std::move(other.impl_)) {
    if (impl_) impl_ = std::make_unique<Impl>(impl_->p_, counters);
}

void PointLighting::shade(std::uint64_t stream, int first_round, int rounds, const Vec3& x,
                          const Vec3& n, const Vec3& ng, double value[3],
                          double variance[3]) {
    impl_->shade(stream, first_round, rounds, x, n, ng, value, variance);
}

DirectLightingStats direct_lighting(const Scene& scene, const double* points,
                                    const double* normals, std::size_t count,
                                    const DirectLightingSettings& settings, double* value,
                                    double* variance, const ProgressFunction& progress) {
    const auto start = std::chrono::steady_clock::now();
    LightingContext context(scene, settings);
    for (std::size_t i = 0; i < 3 * count; ++i)  // Embree's range (issue 11)
        if (!(std::abs(points[i]) <= kLargestTraceableCoordinate))
            throw std::invalid_argument("points: point " + std::to_string(i / 3) +
                                        " has a coordinate beyond ±1e18 m (or not finite)");

    DirectLightingStats stats;
    stats.plan = context.plan;
    tbb::enumerable_thread_specific<PointLighting> shaders(
        [&] { return PointLighting(context); });
    std::atomic<bool> cancel{false};
    std::atomic<std::size_t> done{0};
    std::mutex report;
    // Inside long points: report progress now and then (at most every 50 ms)
    // and stop once it asks to.
    std::atomic<double> last_report{0};
    auto seconds = [&] {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    context.keep_going = [&] {
        const double now = seconds();
        if (progress && now - last_report.load(std::memory_order_relaxed) >= 0.05) {
            std::unique_lock<std::mutex> lock(report, std::try_to_lock);
            last_report = now;
            if (lock.owns_lock() && !progress(double(done.load()) / double(count))) cancel = true;
        }
        return !cancel.load(std::memory_order_relaxed);
    };

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
        if (cancel.load(std::memory_order_relaxed)) return;
        PointLighting& shader = shaders.local();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const Vec3 x(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
            const Vec3 n(normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]);
            try {
                shader.shade(i, 0, settings.rounds, x, n, n, value + 3 * i, variance + 3 * i);
            } catch (const LightingCancelled&) {
                return;
            }
        }
        const std::size_t finished = done.fetch_add(range.size()) + range.size();
        if (progress) {
            std::unique_lock<std::mutex> lock(report, std::try_to_lock);
            if (lock.owns_lock() && !progress(double(finished) / double(count)))
                cancel = true;
        }
    });

    for (const PointLighting& s : shaders) {
        stats.samples += s.counters.samples;
        stats.rays_traced += s.counters.rays;
        stats.mis_systems += s.counters.systems;
        stats.pdf_evaluations += s.counters.pdf_evaluations;
    }
    stats.points = done.load();
    stats.cancelled = cancel.load();
    stats.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return stats;
}

}  // namespace omis
