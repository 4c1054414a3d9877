// PointLighting: shade() = the point's setup, its rounds of samples, its
// estimate; and the public class over Impl.
#include "render/point_lighting_impl.h"

namespace omis {

// shade's rounds: every technique's samples of one round after another, in
// the order of the point's techniques. Techniques whose lights come from a
// selector draw each sample's light into selector_draws_[now], and among
// many lights begin it two samples ahead and finish it one ahead, in the
// slots after it (SelectorDraw).
struct PointLighting::Impl::RoundLoop {
    Impl& impl;
    const Active& active;
    LightSequences& light_sequences;
    const int* counts;
    int first_round, rounds, K;
    const SurfacePoint& centre;
    const Footprint* footprint;
    int now = 0;

    // Technique k's draw j of round r: its index in its stream's sequence.
    std::uint32_t index_of(int k, int r, int j) const {
        const int s = r % K;
        return impl.draws_.start(k, s) +
               (std::uint32_t(r / K) - std::uint32_t(TechniqueDraws::rounds_in_stream(s, first_round, K))) *
                   std::uint32_t(counts[k]) +
               std::uint32_t(j);
    }
    bool draws_ahead(int k) const {
        return !impl.p_.settings.techniques[k].bsdf && !light_sequences.uses_table(k);
    }
    // Moves (r, a, j) to the sample after it in the loop's order; false past
    // the call's last.
    bool advance(int& r, std::size_t& a, int& j) const {
        ++j;
        while (j >= counts[active.all[a]]) {
            j = 0;
            if (++a == active.all.size()) {
                a = 0;
                if (++r == first_round + rounds) return false;
            }
        }
        return true;
    }
    // Finishes the light of the sample after (r, a, j) and begins the one
    // after that.
    void draw_after(int r, std::size_t a, int j) {
        if (!advance(r, a, j)) return;
        int k = active.all[a];
        if (draws_ahead(k)) {
            SelectorDraw& next = impl.selector_draws_[(now + 1) % kSelectorDraws];
            const ScrambledSobol& seq = impl.draws_.sequence(std::size_t(k), r % K);
            const std::uint32_t index = index_of(k, r, j);
            if (next.is(k, seq, index)) impl.finish_selector_draw(next);
            else impl.draw_selector(k, seq, index, centre, footprint, next);
            if (next.light) impl.prefetch_light(next.light->light);
        }
        if (!advance(r, a, j)) return;
        k = active.all[a];
        if (!draws_ahead(k)) return;
        impl.begin_selector_draw(k, impl.draws_.sequence(std::size_t(k), r % K),
                                 index_of(k, r, j), centre, footprint,
                                 impl.selector_draws_[(now + 2) % kSelectorDraws]);
    }
    // Round r's samples into `into` (n_into estimator pairs).
    void round(int r, const Estimators* into, int n_into) {
        const int s = r % K;
        for (std::size_t a = 0; a < active.all.size(); ++a) {
            const int k = active.all[a];
            const ScrambledSobol& seq = impl.draws_.sequence(std::size_t(k), s);
            const bool table = light_sequences.uses_table(k);
            const bool from_selector = draws_ahead(k);
            for (int j = 0; j < counts[k]; ++j) {
                const std::uint32_t index = index_of(k, r, j);
                SelectorDraw* selected = nullptr;
                if (from_selector) {
                    selected = &impl.selector_draws_[now];
                    if (!selected->is(k, seq, index))
                        impl.draw_selector(k, seq, index, centre, footprint, *selected);
                    impl.finish_selector_draw(*selected);  // (done a sample ahead)
                }
                if (impl.draw_next_ahead_) draw_after(r, a, j);
                impl.take_sample(active, a, seq, index, centre, footprint, into, n_into,
                                 table ? light_sequences.draw(k, s, seq, index) : TableDraw{},
                                 selected);
                now = (now + 1) % kSelectorDraws;
            }
        }
    }
};

// The delta lights of round r at its position (one per round where
// positions vary or lights are drawn), into `delta`.
void PointLighting::Impl::add_delta_round(int r, const SurfacePoint& centre,
                                          const Footprint* footprint, DeltaSums& delta) {
    const int K = p_.settings.streams;
    const int s = r % K;
    const std::uint32_t round_in_stream = std::uint32_t(r / K);
    const ScrambledSobol& seq = draws_.sequence(p_.settings.techniques.size(), s);
    SurfacePoint at = centre;
    if (footprint) {
        double fu, fv;
        seq.get_2d(round_in_stream, 0, fu, fv);
        at = footprint->at(fu, fv);
    }
    const Vec3 d = integrand_.delta_lighting(at, seq.get_1d(round_in_stream, 1));
    delta.sum[s] += d;
    delta.sum2 += Vec3(d.x * d.x, d.y * d.y, d.z * d.z);
}

// The point's setup (its techniques, tables and counts), then its rounds,
// then its estimate.
void PointLighting::Impl::shade(std::uint64_t point, int first_round, int rounds,
                                const SurfacePoint& centre, const Footprint* footprint,
                                const int* counts_in, double* value, double* variance,
                                double* own_variance_out, StreamEstimates* streams,
                                const std::vector<DrawnRounds>* earlier) {
    const int* counts = counts_in ? counts_in : p_.settings.samples.data();
    shapes_.new_position();  // invalidates the per-position solid-angle cache
    Active& active = active_scratch_;
    active.clear();
    // Bakes shade a texel again at each pass (and a footprint's tables cost).
    active_for(point, footprint || first_round > 0, centre, footprint, active);
    set_hidden_part(active);
    // A shadowed texel (shadowed_draws) draws m times every count, at every
    // pass: its draw indices are m times those of the counts.
    const int m = draws_per_count_ = active.draws_per_count;
    if (m > 1) {
        scaled_counts_.assign(counts, counts + p_.settings.samples.size());
        for (int& n : scaled_counts_) n *= m;
        counts = scaled_counts_.data();
    }

    // Round r belongs to stream r mod K; each (technique, stream) has its own
    // scrambled sequence, continued from round to round. Delta lights, when
    // positions vary, take one position per round from a sequence of their own.
    const int K = p_.settings.streams;
    const std::uint64_t base = mix64(p_.settings.seed ^ mix64(point));
    draws_.begin_point(base, first_round, earlier, m);
    LightSequences light_sequences(draws_, tables_, point, active.lights);
    const RoundPlan plan = estimate_.plan_rounds(first_round, rounds, variance != nullptr);
    Estimators all{nullptr, nullptr}, per[kMaxSampleStreams] = {};
    if (!active.all.empty())
        estimate_.set_up(main_techniques(active), split_parts(active) ? active.light_mask : active.mask,
                         active.hidden, active.hidden_mask, plan, counts,
                         counts_in != nullptr || m > 1, all, per);

    // Delta lights are evaluated once per round where positions vary or lights
    // are drawn, else once at the centre.
    DeltaSums delta;
    delta.per_round = !p_.delta.empty() && (footprint || p_.plan.sample_delta_lights);
    const bool by_stream_only = plan.by_stream && !plan.in_whole;
    ScopedTimer rounds_timer(setup_timing_ && setup_timing_->on ? &setup_timing_->rounds
                                                                 : nullptr);
    for (SelectorDraw& d : selector_draws_) d.k = -1;  // last call's: other sequences
    RoundLoop loop{*this, active, light_sequences, counts, first_round, rounds, K, centre, footprint};
    for (int r = first_round; r < first_round + rounds; ++r) {
        if (delta.per_round) add_delta_round(r, centre, footprint, delta);
        const Estimators into[2] = {all, per[r % K]};
        if (plan.in_whole && !active.all.empty()) PointEstimate::set_stream(all, r % K);
        loop.round(r, into, by_stream_only ? 2 : 1);
    }
    rounds_timer.stop();
    light_sequences.keep();
    if (!delta.per_round && !p_.delta.empty()) delta.at_centre = integrand_.delta_lighting(centre, 0.0);

    Vec3 own_variance, error_variance;
    if (streams) *streams = StreamEstimates{};
    const Vec3 total =
        estimate_.estimate(!active.all.empty(), plan, all, per, delta, own_variance,
                           error_variance, streams);
    for (int c = 0; c < 3; ++c) {
        value[c] = total[c];
        if (variance) variance[c] = error_variance[c];
        if (own_variance_out) own_variance_out[c] = own_variance[c];
    }
}

PointLighting::PointLighting(const LightingContext& context)
    : impl_(std::make_unique<Impl>(context, counters)) {
    impl_->setup_timing_ = &setup_timing;
}
PointLighting::~PointLighting() = default;
PointLighting::PointLighting(PointLighting&& other) noexcept
    : counters(other.counters), setup_timing(other.setup_timing), impl_(std::move(other.impl_)) {
    if (impl_) impl_ = std::make_unique<Impl>(impl_->p_, counters);
    if (impl_) impl_->setup_timing_ = &setup_timing;
}

void PointLighting::shade(std::uint64_t point, int first_round, int rounds,
                          const SurfacePoint& centre, const Footprint* footprint,
                          double value[3], double variance[3], const int* counts,
                          double own_variance[3], StreamEstimates* streams,
                          const std::vector<DrawnRounds>* earlier) {
    ScopedTimer timer(setup_timing.on ? &setup_timing.shading : nullptr);
    impl_->shade(point, first_round, rounds, centre, footprint, counts, value, variance,
                 own_variance, streams, earlier);
}

int PointLighting::draws_per_count() const { return impl_->draws_per_count_; }

void PointLighting::record_into(AllocationPilot* pilot) {
    if (pilot && pilot->num_techniques() != int(impl_->p_.settings.techniques.size()))
        throw std::invalid_argument("pilot: expected one technique per settings technique");
    impl_->pilot_ = pilot;
}

void PointLighting::shade(std::uint64_t point, int first_round, int rounds, const Vec3& x,
                          const Vec3& n, const Vec3& ng, double value[3],
                          double variance[3]) {
    impl_->shade(point, first_round, rounds, SurfacePoint{x, n, ng}, nullptr, nullptr, value,
                 variance, nullptr, nullptr, nullptr);
}

}  // namespace omis
