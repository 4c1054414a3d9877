// Optimal sample allocation (issue 10, item 2; the paper's future work).
//
// The optimal estimator's variance depends on how many samples each technique
// draws: q = Σ n_k p_k enters A, b and m (SPEC §2). A pilot pass drawn with
// counts n keeps its samples (pdfs and f), and any other allocation's moments
// follow by re-weighting them: (1/R) Σ_s h(x_s)/q(x_s) estimates ∫ h for the
// pilot's q, so with shares w (Σ w = 1, one sample per round)
//     a_ij(w) = ∫ p_i p_j / q_w,  b_i(w) = ∫ p_i f / q_w,  m(w) = ∫ f² / q_w,
// q_w = Σ w_k p_k, and the optimal estimator's variance per sample is
//     V(w) = m(w) − b(w)ᵀ α(w),  A(w) α(w) = b(w)   (summed over channels).
// The shares that minimise V(w) · Σ_k w_k cost_k minimise variance per unit
// time (V scales as 1/samples, the time as samples).
#pragma once

#include <vector>

namespace omis {

class AllocationPilot {
public:
    // counts: the pilot's samples per technique per round. Throws
    // std::invalid_argument on bad sizes or counts.
    AllocationPilot(int num_techniques, int num_channels, const std::vector<int>& counts);

    // One pilot sample (any technique): every technique's pdf at x and f.
    // Null draws (no direction) add nothing and need not be reported.
    void add_sample(const double* pdfs, const double* f);
    // Marks a round complete (the re-weighted sums are divided by the rounds).
    void end_round() { ++rounds_; }

    // V(w) per sample, summed over channels; shares need not be normalised.
    double optimal_variance(const std::vector<double>& shares) const;

    int num_techniques() const { return N_; }
    int rounds() const { return rounds_; }

private:
    int N_, C_;
    std::vector<int> counts_;
    std::vector<double> pdfs_, f_;  // per sample: N pdfs, C values
    int rounds_ = 0;
};

// Shares (summing to 1) minimising V(w)·Σ w_k cost_k, each at least
// min_share (techniques keep drawing: a share of 0 would lose the coverage
// that the pilot could not see). cost: time per sample of each technique.
std::vector<double> optimal_shares(const AllocationPilot& pilot, const std::vector<double>& cost,
                                   double min_share = 0.02);

// Integer counts per round for `total` samples in those shares (largest
// remainder, each at least 1).
std::vector<int> counts_from_shares(const std::vector<double>& shares, int total);

}  // namespace omis
