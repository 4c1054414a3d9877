// The regularised solve of the optimal-MIS system  A α = b  (SPEC §2).
//
// Â and b̂ are Monte Carlo estimates, so the system is exactly singular when two
// techniques coincide or a technique was never seen, nearly singular when two
// almost coincide, and noisy when few samples went in. The rule, in order:
//
//  1. Techniques whose diagonal entry is zero (never seen with non-zero
//     density) get α = 0: nothing was observed that could support any other value.
//  2. The rest is scaled to unit diagonal (so the threshold below does not
//     depend on units) and factored by Cholesky with complete (diagonal)
//     pivoting. Elimination stops when the next pivot falls below
//     τ = 1e-10: the rounding error of Â accumulated in double precision over
//     up to ~10⁶ samples per system; below it the pivot's direction is
//     numerically undetermined. Unpivoted techniques get α = 0. Collinear but
//     resolvable techniques are kept: the fitted control variate g = Σ α_k p_k
//     is well defined even when the individual α_k are not.
//  3. α is kept only when it is predicted to beat the balance heuristic after
//     paying for its own estimation. Solving Â α = b̂ is the least-squares fit
//     of Z = f/q by the regressors p_k/q (n plays the intercept), so classical
//     control-variate regression (Lavenberg & Welch 1981) applies: with k free
//     coefficients (rank − 1 when n lies in the kept span, since that
//     direction is inert) fitted from S samples, the unbiased residual
//     variance is V̂(α)·S/(S − k − 1), and estimating α inflates it by
//     (S − 2)/(S − k − 2). α stays iff that beats the balance heuristic's
//     V̂(0)·S/(S − 1), and with S ≤ k + 2 never. V̂ here is the pooled sample
//     variance of Z (pooled_round_variance), which is never negative; the
//     stratified plug-in (round_variance) can be, with few samples. This rule
//     removes the "salt & pepper" of few-sample solves and degrades
//     toward the balance heuristic exactly when the gain does not pay.
//
//  4. A kept α is shrunk toward the balance solution: α ← λ α with the
//     positive-part James–Stein factor λ = 1 − k·σ̂²_res/(S·ΔV̂), where ΔV̂ is
//     the in-sample variance reduction of the fit and k·σ̂²_res/S its expected
//     value when the true gain is zero. λ minimises the variance of the
//     control variate λ·α̂ when α̂ = α* + ε with Cov ε ≈ σ²_res A⁻¹/S. It is a
//     smooth version of rule 3: full α when the gain is clear, balance when
//     it is within noise. Bias: none added for optimal-progressive (α still
//     depends on earlier rounds only); for optimal-direct it scales the
//     in-sample correction, so it scales that bias by λ ≤ 1 as well.
//
// Only the component of α orthogonal to n matters: adding t·n changes neither
// the estimate nor its variance (Σ_i n_i a_ij = 1, Σ_i n_i b_i = F). So an α
// proportional to n, up to rounding, *is* the balance heuristic.
#pragma once

#include <array>
#include <cstddef>

namespace omis {

constexpr int kMaxSolveTechniques = 32;
constexpr int kMaxSolveChannels = 4;

// Fixed-size storage: a solve runs once per shading point, and heap
// allocations would cost about as much as the solve itself.
struct SolveResult {
    // α of technique k, channel c at [k*C + c]; only the first N·C entries are set.
    std::array<double, kMaxSolveTechniques * kMaxSolveChannels> alpha;
    int rank = 0;               // techniques kept by the pivoted factorisation
    int free_coefficients = 0;  // k of rule 3
    std::array<bool, kMaxSolveChannels> kept{};  // per channel: false when rule 3 fell back to balance
    std::array<double, kMaxSolveChannels> shrink{};  // per channel: rule 4's λ in [0, 1] (α was scaled by it)
    // Per kept channel: pooled_round_variance at the returned α (else 0).
    std::array<double, kMaxSolveChannels> fit_variance{};
};

// Moments accumulated over the samples (all divided by R, or all not):
//   a[i*N+j] = Σ p_i p_j / q²,  b[i*C+c] = Σ p_i f_c / q²,  m[c] = Σ f_c² / q².
// counts[k] = n_k, total_samples = S (rule 3). At most 32 techniques and 4
// channels; beyond that α = 0 (the caller validates sizes).
// min_samples_per_coefficient: α = 0 (balance) while S < that × (k + 1); an α
// applied to fresh samples (optimal-progressive) pays its whole estimation
// error k·V/S, which the rule-4 estimate of the gain cannot see reliably from
// a handful of samples.
SolveResult solve_optimal_alpha(int N, int C, const double* a, const double* b,
                                const double* m, const int* counts,
                                double total_samples,
                                double min_samples_per_coefficient = 0);

// Pooled (unstratified) sample variance of one round's control-variate sum:
// an upper bound of the stratified one that is never negative.
double pooled_round_variance(int N, int C, int c, const double* a, const double* b,
                             const double* m, const int* counts, const double* alpha);

// Variance of one round's control-variate sum (SPEC §2), stratified by
// technique, for a given α and channel c:
//     V(α) = m − 2 α·b + αᵀ A α − Σ_t n_t (b − A α)_t².
// Exact with exact moments; with few-sample estimates it is noisy (clamped at 0).
double round_variance(int N, int C, int c, const double* a, const double* b,
                      const double* m, const int* counts, const double* alpha);

}  // namespace omis
