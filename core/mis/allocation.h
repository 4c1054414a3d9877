// Optimal sample allocation (issue 10, item 2; the paper's future work).
//
// The optimal estimator's variance depends on how many samples each technique
// draws: q = Σ n_k p_k enters A, b and m (SPEC §2). A pilot pass drawn with
// counts n keeps its samples (pdfs and f), and any other allocation's moments
// follow by re-weighting them: (1/R) Σ_s h(x_s)/q(x_s) estimates ∫ h for the
// pilot's q, so with shares w (one sample per round)
//     a_ij(w) = ∫ p_i p_j / q_w,  b_i(w) = ∫ p_i f / q_w,  m(w) = ∫ f² / q_w,
// q_w = Σ w_k p_k, and the optimal estimator's variance per sample is
//     V(w) = m(w) − b(w)ᵀ α(w),  A(w) α(w) = b(w)   (summed over channels).
// The shares that minimise V(w) · Σ_k w_k cost_k minimise variance per unit
// time (V scales as 1/samples, the time as samples).
//
// A region (a bake's tile) pools the pilot samples of many points: each
// point's f is scaled by 1/its own estimate (end_point), so every point weighs
// alike — the pooled objective is the mean relative variance, with one α for
// the region (a slight overestimate of each point's own optimum, but stable
// where a point's few samples are not).
#pragma once

#include <cstddef>
#include <vector>

namespace omis {

class AllocationPilot {
public:
    // counts: the pilot's samples per technique per round (a technique with
    // count 0 takes no part and keeps share 0). Throws std::invalid_argument
    // on bad sizes or counts.
    AllocationPilot(int num_techniques, int num_channels, const std::vector<int>& counts);

    // One pilot sample (any technique): every technique's pdf at x and f.
    // Null draws (no direction) add nothing and need not be reported.
    void add_sample(const double* pdfs, const double* f);
    // Marks a round complete (the re-weighted sums are divided by the rounds).
    void end_round() { ++rounds_; }
    // A region's point is complete after `rounds` rounds: its samples' f are
    // scaled by `scale` (1/the point's estimate; 0 drops their f).
    void end_point(double scale, int rounds);
    // The work of one draw of `technique` (any unit, the same for all).
    void add_work(int technique, double units);

    // V(w) per sample, summed over channels; shares need not be normalised.
    // gradient, if given, receives −∂V_u/∂w_k at the normalised shares, V_u
    // the variance of Σ_k w_k samples (V_u = V at Σ w = 1; homogeneous of
    // degree −1, so Σ_k w_k ∂V_u/∂w_k = −V_u).
    double optimal_variance(const std::vector<double>& shares,
                            std::vector<double>* gradient = nullptr) const;
    // Mean work per draw of each technique (1 where none was reported).
    std::vector<double> cost() const;

    int num_techniques() const { return N_; }
    int rounds() const { return rounds_; }
    std::size_t samples() const { return q_.size(); }
    const std::vector<int>& counts() const { return counts_; }

private:
    int N_, C_;
    std::vector<int> counts_;
    std::vector<double> pdfs_, f_, q_;  // per sample: N pdfs, C values, the pilot's q
    std::size_t point_begin_ = 0;       // first sample of the open point
    std::vector<double> work_, draws_;  // per technique
    int rounds_ = 0;
};

// Shares (summing to 1) minimising V(w)·Σ_k w_k cost_k, each at least
// min_share (techniques keep drawing: a share of 0 would lose the coverage
// that the pilot could not see), techniques with pilot count 0 at 0. Never
// worse by the pilot's own estimate than the pilot's own shares. cost: time
// per sample of each technique. Throws std::invalid_argument on bad cost or
// min_share, std::logic_error without a complete round.
std::vector<double> optimal_shares(const AllocationPilot& pilot, const std::vector<double>& cost,
                                   double min_share = 0.02);

// Integer counts per round for `total` samples in those shares (largest
// remainder, each technique with a positive share at least 1; ties to the
// lower index).
std::vector<int> counts_from_shares(const std::vector<double>& shares, int total);

}  // namespace omis
