// The pass schedule of a bake (bake_schedule.h): how many rounds each pass
// takes under a sample, time or noise budget, and what the passes cost.
#include "bake/bake_schedule.h"

#include <algorithm>
#include <cmath>

#include "bake/dyadic_schedule.h"

namespace omis::bake_detail {

PassSchedule::PassSchedule(const Scene& scene, const BakeSettings& settings,
                           const LightingContext& context, const SampleBudget& budget,
                           const BakeLayout& layout, const BakeResult& result, std::uint64_t shape,
                           Clock::time_point start)
    : scene_(scene), settings_(settings), context_(context), budget_(budget), layout_(layout),
      result_(result), shape_(shape), start_(start),
      progressive_(settings.time_budget > 0 || settings.noise_target > 0) {}

void PassSchedule::start(bool allocate) {
    // Under a time budget the first pass — the part a budget cannot cut — is
    // a single round, so small budgets are not eaten by it; it also measures
    // what a round costs here. The optimal strategies solve per pass, and a
    // one-round pass falls back to balance (too few samples to fit α): its
    // estimate, averaged in by samples, would add balance's far larger
    // variance per sample. For them it is a probe: the result if the budget
    // ends there, else replaced by the passes after it, which start again at
    // round 0 (the same draws) and take rounds_per_pass or more.
    const bool under_time = settings_.time_budget > 0;
    const bool optimal = fits_per_pass();
    next_rounds_ = !progressive_ ? budget_.full_rounds
                   : under_time  ? 1
                                 : settings_.rounds_per_pass;
    later_min_rounds_ = under_time && optimal ? settings_.rounds_per_pass : 1;
    probe_ = under_time && optimal && budget_.full_rounds > 1;
    last_done_ = budget_.last.empty();
    dyadic_ = under_time && settings_.noise_target <= 0 && !allocate;
    if (allocate) {
        probe_ = false;  // the first pass is the allocation's pilot, not replaced
        // A bake of a sample budget: a quarter of it is the pilot, the rest one pass.
        if (!progressive_) next_rounds_ = std::max(1, budget_.full_rounds / 4);
    }
}

// The next pass of the schedule, cut to what the time budget still fits (as
// the passes so far predict its duration); false when the bake ends here.
bool PassSchedule::plan_pass(Pass& pass) {
    // A pass meant to take the time left ends the bake, unless the prediction
    // behind it was pessimistic (early passes carry the warm-up) and a tenth
    // of the budget or more is still left: a budget is time to use.
    if (time_ends_) {
        if (settings_.time_budget - elapsed() < 0.1 * settings_.time_budget) {
            status_ = BakeStatus::TimeBudget;
            return false;
        }
        time_ends_ = false;
    }
    if (dyadic_ && pass_count_ > 0 && done_rounds_ < budget_.full_rounds)
        return plan_dyadic_pass(pass);
    pass.first_round = done_rounds_;
    if (done_rounds_ < budget_.full_rounds) {
        pass.rounds = std::min(next_rounds_, budget_.full_rounds - done_rounds_);
    } else if (!last_done_) {
        pass.rounds = 1;
        pass.counts = budget_.last.data();
    } else {
        return false;
    }
    if (settings_.time_budget > 0 && pass_count_ > 0) {
        const double fits = timer_.fit(settings_.time_budget - elapsed());
        const double fit_rounds = fits / budget_.per_round;
        const int rounds_left = budget_.full_rounds - done_rounds_;
        // When the time left would cut the pass after this one short (less
        // than this pass fits again), this pass takes all of it and is the
        // last: a small final pass adds few samples, and as its estimate joins
        // the others' as an independent one, its poor error raises the estimate.
        if (!pass.counts && fit_rounds < 2.0 * pass.rounds && fit_rounds < rounds_left) {
            pass.rounds = int(std::max(0.0, fit_rounds));
            time_ends_ = true;
            // An optimal strategy skips a last pass far smaller than the one
            // before: its own solve (balance, below 2(k + 1) samples) joins
            // the others' and raises the error more than its samples lower it.
            if (fits_per_pass() && 4 * pass.rounds < last_pass_rounds_)
                pass.rounds = 0;
        } else if (!pass.counts && settings_.noise_target <= 0) {
            // Few passes: each costs a fixed part (per-point set-up, the
            // optimal strategies' solve). A pass takes half the time left, as
            // the passes so far predict, but at most 4× the pass before it,
            // whose time predicts its own: one round (milliseconds) measures
            // the cost too roughly to size a pass of seconds.
            pass.rounds = std::min({rounds_left, std::max(pass.rounds, int(0.5 * fit_rounds)),
                                    4 * last_pass_rounds_});
        }
        if (pass.rounds < 1 || (pass.counts && fits < budget_.last_samples)) {
            status_ = BakeStatus::TimeBudget;
            return false;
        }
    }
    pass.samples = pass.counts ? std::uint32_t(budget_.last_samples)
                               : std::uint32_t(pass.rounds * budget_.per_round);
    return true;
}

// The next pass of a time budget, to a power of two of rounds or a tail after
// one (dyadic_schedule.h).
bool PassSchedule::plan_dyadic_pass(Pass& pass) {
    const double fit = timer_.fit(settings_.time_budget - elapsed()) / budget_.per_round;
    // An optimal strategy's probe is replaced by a first net of
    // rounds_per_pass only where that still fits. Where it does not (small
    // budgets, costly first passes: the race's 0.25 s on 64 lights ended at
    // 0.11 s with the probe alone), the probe stays as the first round and the
    // passes after it follow as for balance (below 2(k + 1) samples a pass
    // solves as balance anyway).
    DyadicPass next;
    if (replace_probe_) {
        const PassAfterProbe after =
            pass_after_probe(last_pass_rounds_, fit, later_min_rounds_, budget_.full_rounds);
        next = after.pass;
        if (after.keep_probe) {
            replace_probe_ = false;
            done_rounds_ = last_pass_rounds_;
            if (power_of_two_floor(done_rounds_) == done_rounds_) record_net_end();
        }
    } else {
        next = next_dyadic_pass(done_rounds_, fit, later_min_rounds_,
                                budget_.full_rounds - done_rounds_);
    }
    if (next.rounds < 1) {
        status_ = BakeStatus::TimeBudget;
        return false;
    }
    pass.first_round = done_rounds_;
    pass.rounds = next.rounds;
    pass.samples = std::uint32_t(pass.rounds * budget_.per_round);
    pass.tail = next.tail;
    if (next.tail && 2 * next.rounds != done_rounds_)
        pass.weight = budget_.per_round * tail_weight(power_of_two_floor(done_rounds_),
                                                      next.rounds, rate_.tail_alpha());
    return true;
}

// At a power-of-two end: how much the running means moved since the last one
// (mean square relative change over the baked texels, as the race measures
// error: ε = 1 % of the mean keeps dark texels finite), for NetRate.
void PassSchedule::record_net_end() {
    double sum_change = 0, sum_value = 0;
    std::size_t covered = 0;
    const bool first = net_end_luminance_.empty();
    if (first) net_end_luminance_.assign(layout_.count, 0.f);
    for (std::size_t i = 0; i < layout_.count; ++i)
        if (layout_.covered(i)) {
            const float* v = &result_.value[3 * i];
            sum_value += luminance(Vec3(v[0], v[1], v[2]));
            ++covered;
        }
    const double eps = 0.01 * (covered ? sum_value / double(covered) : 0.0);
    for (std::size_t i = 0; i < layout_.count; ++i) {
        if (!layout_.covered(i)) continue;
        const float* v = &result_.value[3 * i];
        const double now = luminance(Vec3(v[0], v[1], v[2]));
        const double d = now - net_end_luminance_[i];
        if (std::isfinite(d)) sum_change += d * d / (now * now + eps * eps + 1e-300);
        net_end_luminance_[i] = float(now);
    }
    rate_.add(done_rounds_, first || !covered ? 0.0 : sum_change / double(covered));
}

// A time budget's first pass where an earlier bake of the same shape measured
// its passes (Scene::measured_pass_cost): sized by that measure
// (measured_first_pass), in place of the one-round pass that
// otherwise measures the cost — and which an optimal strategy then replaces
// (its probe). On emissive_mesh at 128² a round takes 12–15 ms and a first
// pass ~6.5 ms more: in a 0.05 s budget the probe and one more round ended at
// one or two samples by a few ms either way, where two rounds in one pass
// take 37 ms (budgets.txt). Not taken below two rounds: one round is the
// probe's own size.
void PassSchedule::size_first_pass() {
    if (!dyadic_) return;
    const auto cost = scene_.measured_pass_cost(shape_);
    if (!cost || !(cost->round > 0)) return;
    const double left = settings_.time_budget - elapsed() - cost->first_pass_fixed;
    const int rounds = measured_first_pass(left / cost->round, budget_.full_rounds);
    if (rounds < 2) return;
    next_rounds_ = rounds;
    probe_ = false;  // a first net (or one too small for a solve: as a kept probe)
}

// What this bake's passes cost, for the next bake of its shape: the first
// pass's fixed part, and a round at the rate the last pass ran, blended with
// the earlier bakes' (blend_round_cost).
void PassSchedule::remember_pass_cost() const {
    const double round = timer_.per_sample() * budget_.per_round;
    if (status_ == BakeStatus::Cancelled || first_pass_fixed_ < 0 || !(round > 0)) return;
    Scene::PassCost earlier;
    if (const auto known = scene_.measured_pass_cost(shape_)) earlier = *known;
    const BlendedRoundCost blend =
        blend_round_cost(earlier.round, earlier.rounds, round, last_pass_rounds_);
    scene_.remember_pass_cost(shape_, {first_pass_fixed_, blend.seconds, blend.rounds});
}

// The probe's place in the schedule: its nets and rate start again.
void PassSchedule::forget_probe() {
    replace_probe_ = false;
    net_end_luminance_.clear();
    rate_.reset();
}

void PassSchedule::after_pass(const Pass& pass) {
    if (pass.counts) last_done_ = true;
    if (!pass.counts) last_pass_rounds_ = pass.rounds;
    if (probe_ && pass_count_ == 1) {
        replace_probe_ = true;  // the next pass, if any, starts again at round 0
    } else {
        done_rounds_ += pass.rounds;
        if (dyadic_ && power_of_two_floor(done_rounds_) == done_rounds_) record_net_end();
    }
    // Doubling keeps the per-pass cost small; under a noise target passes
    // grow by half only, so a texel overshoots its target by at most
    // √1.5 ≈ 1.22 in error.
    const double growth = settings_.noise_target > 0 ? 1.5 : 2.0;
    next_rounds_ = int(std::min<double>(
        1 << 24, std::max<double>(later_min_rounds_, std::ceil(growth * pass.rounds))));
    if (!progressive_) next_rounds_ = budget_.full_rounds;  // after an allocation pilot
}

// The pass that ran, for the timer. Of the first pass, only what a later pass
// of its size repeats: all of it but the set-up of the tables its points keep
// (PointLighting::SetupTiming: 8–39 % of a one-round first pass on the race's
// scenes, which made the second pass look that much longer and could end a
// 0.05 s budget a round early); and of that, the part outside the rounds'
// sampling is the fixed part of every later pass.
void PassSchedule::time_pass(std::uint32_t samples, double seconds,
                             tbb::enumerable_thread_specific<PointLighting>& shaders) {
    if (pass_count_ > 0) {
        timer_.add(samples, seconds);
        return;
    }
    double setup = 0, shading = 0, rounds = 0;
    for (PointLighting& shader : shaders) {
        setup += shader.setup_timing.kept_setup;
        shading += shader.setup_timing.shading;
        rounds += shader.setup_timing.rounds;
        shader.setup_timing = {};
    }
    if (!(shading > 0)) {
        timer_.add(samples, seconds);
        return;
    }
    const double repeated = std::clamp(1.0 - setup / shading, 0.0, 1.0);
    first_pass_fixed_ = seconds * std::max(0.0, 1.0 - rounds / shading);
    timer_.add(samples, seconds * repeated);
    timer_.set_fixed(seconds * std::max(0.0, repeated - rounds / shading));
}

}  // namespace omis::bake_detail
