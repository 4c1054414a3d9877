#include "bake/dyadic_schedule.h"

#include <algorithm>
#include <cmath>

namespace omis {

int power_of_two_floor(int n) {
    int p = 1;
    while (p <= n / 2) p *= 2;
    return p;
}

namespace {

int power_of_two_ceil(int n) {
    int p = 1;
    while (p < n) p *= 2;
    return p;
}

}  // namespace

DyadicPass next_dyadic_pass(int done, double fit, int min_rounds, int rounds_left) {
    DyadicPass pass;
    if (rounds_left <= 0 || !(fit >= 1)) return pass;
    const int can = int(std::min<double>(fit, rounds_left));
    if (done == 0) {  // after a dropped probe: the first net
        const int first = power_of_two_ceil(std::max(1, min_rounds));
        if (first <= can) pass.rounds = first;
        else if (rounds_left <= can) pass.rounds = rounds_left;
        return pass;
    }
    const int net = power_of_two_floor(done);
    if (done == net) {
        // A sample budget's last rounds are taken as asked, where they fit.
        if (rounds_left <= done && rounds_left <= can) {
            pass.rounds = rounds_left;
            return pass;
        }
        // To 8N or 4N wherever its rounds fit with kGrowthMargin to spare:
        // reaching it by 2N first costs one more pass (its fixed part) for
        // the same net, but measures the cost again half-way.
        for (int growth = kMostGrowth; growth >= 4; growth /= 2) {
            const double rounds = double(growth - 1) * done;
            if (rounds <= kGrowthMargin * fit && rounds <= rounds_left) {
                pass.rounds = int(rounds);
                return pass;
            }
        }
        if (done <= can) {
            pass.rounds = done;  // to 2N
            return pass;
        }
    }
    // A tail: aligned after the blocks so far, and smaller than the last one
    // (two equal blocks would be a larger net, whose points weigh alike).
    const int last_block = done & -done;
    const int rounds = std::min(power_of_two_floor(can), last_block / 2);
    if (rounds >= 1 && kSmallestTail * rounds >= net) {
        pass.rounds = rounds;
        pass.tail = true;
    }
    return pass;
}

PassAfterProbe pass_after_probe(int probe_rounds, double fit, int min_rounds,
                                int rounds_total) {
    PassAfterProbe next;
    next.pass = next_dyadic_pass(0, fit, min_rounds, rounds_total);
    if (next.pass.rounds >= 1) return next;
    next.keep_probe = true;
    next.pass = next_dyadic_pass(probe_rounds, fit, 1, rounds_total - probe_rounds);
    return next;
}

int measured_first_pass(double fit, int rounds_total) {
    const double fits = kGrowthMargin * fit;
    if (rounds_total <= 0 || !(fits >= 1)) return 0;
    if (rounds_total <= fits) return rounds_total;
    // Room for the pass to 2N after it where 4 rounds fit: two passes measure
    // how the error falls (convergence.h), which the bake reports.
    return power_of_two_floor(int(fits >= 4 ? fits / 2 : fits));
}

BlendedRoundCost blend_round_cost(double earlier, double earlier_rounds, double now,
                                  double rounds) {
    const double w = earlier > 0 && earlier_rounds > 0 ? 0.5 * earlier_rounds : 0.0;
    if (!(rounds > 0)) return {earlier, w};
    return {(now * rounds + earlier * w) / (rounds + w), rounds + w};
}

void PassTimer::set_fixed(double seconds) { fixed_ = std::max(0.0, seconds); }

void PassTimer::add(double samples, double seconds) {
    samples_ = samples;
    seconds_ = seconds;
}

double PassTimer::fixed_part() const { return std::min(fixed_, kMostFixed * seconds_); }

double PassTimer::per_sample() const {
    return samples_ > 0 ? (seconds_ - fixed_part()) / samples_ : 0;
}

double PassTimer::fit(double seconds) const {
    const double b = per_sample();
    return b > 0 ? (seconds - fixed_part()) / b : 0;
}

double tail_weight(int net_rounds, int tail_rounds, double alpha) {
    return double(net_rounds) * std::pow(double(tail_rounds) / net_rounds, alpha);
}

void NetRate::add(int end_rounds, double mean_square_change) {
    if (!ends_.empty()) changes_.push_back(mean_square_change);
    ends_.push_back(end_rounds);
    if (changes_.size() < 2) return;
    const double n0 = ends_[ends_.size() - 3], n1 = ends_[ends_.size() - 2], n2 = ends_.back();
    const double d01 = changes_[changes_.size() - 2], d12 = changes_.back();
    measured_ = true;
    if (!(d01 > 0) || !(d12 > 0) || !std::isfinite(d01 / d12)) {
        alpha_ = kMinAlpha;
        return;
    }
    // The ratio of consecutive changes under error ∝ N^-α; it grows with α.
    auto ratio = [&](double a) {
        return (std::pow(n0, -a) - std::pow(n1, -a)) / (std::pow(n1, -a) - std::pow(n2, -a));
    };
    const double want = d01 / d12;
    double lo = kMinAlpha, hi = kMaxAlpha;
    if (want <= ratio(lo)) {
        alpha_ = lo;
        return;
    }
    if (want >= ratio(hi)) {
        alpha_ = hi;
        return;
    }
    for (int i = 0; i < 40; ++i) {
        const double mid = 0.5 * (lo + hi);
        (ratio(mid) < want ? lo : hi) = mid;
    }
    alpha_ = 0.5 * (lo + hi);
}

}  // namespace omis
