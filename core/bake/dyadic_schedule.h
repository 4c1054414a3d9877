// The passes of a time-budget bake end on powers of two.
//
// A point draws its rounds from one Owen-scrambled Sobol sequence per
// technique. Its first 2^k points form a complete net, and on smooth lighting
// the mean over a net is far more accurate than over a count in between: the
// race's principled_r0 scene (one run, relMSE at equal samples) gives
// 4.6e-6 at 16 rounds, 5.1e-6 at 24 and 1.2e-6 at 32; its error falls ~N^-2.2
// from net to net and hardly at all in between. So under a time budget the
// passes take a point from N rounds to 2N or 4N. When even 2N no longer fits,
// the time left takes a tail block of R = 2^j < N rounds (rounds N..N+R, a net
// of its own). A tail of N/2 joins at equal weight: with the net's first half
// it is a digital net of N points (the indices below 2N whose second-highest
// bit is 0), and 1.5N
// rounds measured 1.7× less error than N on the same scene (6.8e-7). A
// smaller tail joins with the weight its error allows: equal weights made
// 1.25N worse than N (2.0e-6); with error ∝ rounds^-α, inverse-error weights
// give the tail N·(R/N)^α where equal weights would give R (1.1e-6). α comes
// from the bake itself (NetRate); α = 1, independent draws, gives equal
// weights.
//
// Both blocks are unbiased estimates, so any fixed weights keep the mean
// unbiased; α is measured over the whole image, so a texel's own samples move
// its weights negligibly.
#pragma once

#include <vector>

namespace omis {

struct DyadicPass {
    int rounds = 0;     // 0: the bake ends here
    bool tail = false;  // a tail block after the last complete net
};

// The next pass after `done` rounds (a power of two, or 0 when a probe pass
// was dropped; a power of two plus tails after a tail), when the time left
// fits `fit` more rounds and at most `rounds_left` remain. `min_rounds`: the
// smallest pass from round 0. Growth: to 8N while 7N rounds fit in
// kGrowthMargin of the time left, else to 4N while 3N do, else to 2N while N
// fit; else a tail, as large as fits but no larger than half the block
// before it (blocks stay aligned nets), and none smaller than
// N/kSmallestTail (a tiny block adds little and each pass costs a fixed
// part).
constexpr int kSmallestTail = 16;
// A pass runs up to ~1.2× its predicted duration (PassTimer, p90 over 114
// passes on the shared machine, bench/results/budgets.txt): a pass
// predicted to take all the time left would end the budget that much late.
// (Half, as before, made emissive_mesh's 0.25 s bake 1, +1, +1 rounds where
// 1, +3 fit.)
constexpr double kGrowthMargin = 0.8;
// Every pass repeats a fixed part (0.56–0.65 of a round on emissive_mesh:
// callgrind of omis_bench_first_pass --passes, budgets.txt), so a net is
// reached in as few passes as fit; growth stops at 8N so that the ends 1, 8,
// 16 still measure α before a tail (NetRate::tail_alpha).
constexpr int kMostGrowth = 8;
DyadicPass next_dyadic_pass(int done, double fit, int min_rounds, int rounds_left);

// After an optimal strategy's probe of `probe_rounds` (done = 0): the first
// net of at least min_rounds from round 0, replacing the probe; where that no
// longer fits, the probe is kept as the first rounds (`keep_probe`) and the
// pass after it follows as for done = probe_rounds.
struct PassAfterProbe {
    DyadicPass pass;
    bool keep_probe = false;
};
PassAfterProbe pass_after_probe(int probe_rounds, double fit, int min_rounds, int rounds_total);

// A time budget's first pass where an earlier bake of the same shape measured
// what a round costs (Scene::measured_pass_cost), `fit` rounds fitting in the
// time left: all `rounds_total` where they fit in kGrowthMargin of it; else
// the largest net N whose pass to 2N fits after it, or where not even 4
// rounds fit, the largest net that fits; 0 when not even one round does.
int measured_first_pass(double fit, int rounds_total);

// What a round costs, from an earlier measure over `earlier_rounds` rounds and
// this bake's over `rounds`: their mean weighted by rounds, the earlier one's
// halved (the machine's load moves between bakes). A one-round pass carries
// its cold start (emissive_mesh 128²: ~19 ms against ~15 ms a round in a
// two-round pass), so one such bake alone does not undo a longer measure.
// Returns the cost and its weight in rounds.
struct BlendedRoundCost {
    double seconds = 0, rounds = 0;
};
BlendedRoundCost blend_round_cost(double earlier, double earlier_rounds, double now, double rounds);

// The largest power of two ≤ n (n ≥ 1).
int power_of_two_floor(int n);

// A tail block's weight in the running mean, in rounds: N·(R/N)^α for a tail
// of R rounds after a net of N rounds.
double tail_weight(int net_rounds, int tail_rounds, double alpha);

// Predicts a time-budget pass's duration as a + b·samples: a, the fixed cost
// of a pass (per-point set-up, solves, thread wake-up), as the first pass
// measured it (set_fixed; 0: in proportion to the last pass); b from the last
// pass, whose time is nearest the load the next one meets. Not from the slope
// between the last two passes: on the shared machine passes of 4 and 8 rounds
// took 0.390 and 0.392 s, the slope made a round nearly free, and a 2 s
// budget ran a pass of 48 rounds to 3.36 s (bench/results/budgets.txt).
class PassTimer {
public:
    // A later pass's fixed part as the first pass measured it: every pass
    // repeats ~0.8 round of per-point work (bench "area", 128²); in
    // proportion to a one-round first pass the second was predicted
    // 1.14–1.82× its duration, with this 0.90–1.66× (budgets.txt).
    void set_fixed(double seconds);
    void add(double samples, double seconds);
    // The most samples per point a pass can take in `seconds`.
    double fit(double seconds) const;
    // Seconds per sample per point beyond the fixed part, as the last pass
    // measured it (0 before any).
    double per_sample() const;

private:
    static constexpr double kMostFixed = 0.75;  // of the last pass: its rounds cost too
    double fixed_part() const;                  // of the next pass, in seconds
    double samples_ = 0, seconds_ = 0;          // of the last pass
    double fixed_ = 0;
};

// The rate α of error ∝ rounds^-α of the running means, from how much they
// change between consecutive power-of-two ends: with nested means, the mean
// square change from N0 to N1 rounds is e(N0) − e(N1), so two consecutive
// changes fix α (independent of the scale of e). Before two changes are
// known, or when the changes do not fall, α = 1 (independent draws).
class NetRate {
public:
    static constexpr double kMinAlpha = 1.0, kMaxAlpha = 3.0;
    // A change measured from the previous end to `end_rounds`; the first call
    // only records the end.
    void add(int end_rounds, double mean_square_change);
    void reset() { *this = NetRate{}; }
    double alpha() const { return alpha_; }
    bool measured() const { return measured_; }
    // The α a tail weighs by (tail_weight): the measured one, else
    // kUnmeasuredAlpha. With weights from an assumed a where the error falls
    // as N^-α, a tail of R = rN raises the net's error only where
    // r^(a−α) > 2 + r^a: a = 2 never does for α ≤ 2 (and by ≤ 1.2 % at
    // α = 2.5, r = 1/8), while a = 1 — equal weights — raised principled_r0's
    // (α ≈ 2.2: 1.25N worse than N, above). Fewer ends are measured where a
    // pass grows 8×.
    static constexpr double kUnmeasuredAlpha = 2.0;
    double tail_alpha() const { return measured_ ? alpha_ : kUnmeasuredAlpha; }

private:
    std::vector<int> ends_;
    std::vector<double> changes_;  // changes_[i]: from ends_[i] to ends_[i + 1]
    double alpha_ = 1.0;
    bool measured_ = false;
};

}  // namespace omis
