#include "mis/solver.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace omis {
namespace {

// Numerical rank threshold on unit-diagonal pivots (see solver.h, rule 2).
constexpr double kPivotThreshold = 1e-10;
constexpr int kMaxTechniques = kMaxSolveTechniques;
constexpr int kMaxChannels = kMaxSolveChannels;

// The seen techniques' system scaled to unit diagonal, factored in place.
// Left uninitialised on purpose: only the M×M block is used, and clearing
// 8 KB per solve would dominate its cost.
struct ScaledSystem {
    int M = 0;     // techniques seen (rule 1)
    int rank = 0;  // pivots kept (rule 2)
    std::array<int, kMaxTechniques> seen;      // scaled index → technique
    std::array<double, kMaxTechniques> scale;  // 1/√a_ii
    std::array<int, kMaxTechniques> perm;      // pivot order
    std::array<double, kMaxTechniques * kMaxTechniques> L;
    std::array<double, kMaxTechniques * kMaxChannels> rhs;
};

// Rule 1 and the unit-diagonal scaling: S = D A D and D b over the
// techniques seen with non-zero density.
void scale_seen(int N, int C, const double* a, const double* b, ScaledSystem& s) {
    s.M = 0;
    for (int i = 0; i < N; ++i) {
        const double d = a[i * N + i];
        if (d > 0 && std::isfinite(d)) {
            s.seen[s.M] = i;
            s.scale[s.M] = 1.0 / std::sqrt(d);
            ++s.M;
        }
    }
    const int M = s.M;
    for (int i = 0; i < M; ++i) {
        for (int j = 0; j < M; ++j)
            s.L[i * M + j] = a[s.seen[i] * N + s.seen[j]] * s.scale[i] * s.scale[j];
        for (int c = 0; c < C; ++c) s.rhs[i * C + c] = b[s.seen[i] * C + c] * s.scale[i];
    }
}

// Rule 2: Cholesky with diagonal pivoting, in place (lower triangle), stopping
// at the first pivot below the threshold.
void pivoted_cholesky(ScaledSystem& s) {
    const int M = s.M;
    auto& L = s.L;
    auto& perm = s.perm;
    for (int i = 0; i < M; ++i) perm[i] = i;
    s.rank = 0;
    for (int k = 0; k < M; ++k) {
        int p = k;
        for (int i = k + 1; i < M; ++i)
            if (L[perm[i] * M + perm[i]] > L[perm[p] * M + perm[p]]) p = i;
        std::swap(perm[k], perm[p]);
        const int pk = perm[k];
        const double pivot = L[pk * M + pk];
        if (!(pivot > kPivotThreshold)) break;
        const double root = std::sqrt(pivot);
        L[pk * M + pk] = root;
        for (int i = k + 1; i < M; ++i) L[perm[i] * M + pk] /= root;
        for (int i = k + 1; i < M; ++i) {
            const int pi = perm[i];
            for (int j = k + 1; j <= i; ++j) {
                const int pj = perm[j];
                L[pi * M + pj] -= L[pi * M + pk] * L[pj * M + pk];
                L[pj * M + pi] = L[pi * M + pj];
            }
        }
        ++s.rank;
    }
}

// Forward and back substitution over the pivoted block, per channel; α of the
// unpivoted techniques stays 0.
void substitute(int C, const ScaledSystem& s, double* alpha) {
    const int M = s.M;
    const auto& L = s.L;
    const auto& perm = s.perm;
    std::array<double, kMaxTechniques> y;
    for (int c = 0; c < C; ++c) {
        for (int k = 0; k < s.rank; ++k) {
            const int pk = perm[k];
            double sum = s.rhs[pk * C + c];
            for (int j = 0; j < k; ++j) sum -= L[pk * M + perm[j]] * y[j];
            y[k] = sum / L[pk * M + pk];
        }
        for (int k = s.rank - 1; k >= 0; --k) {
            const int pk = perm[k];
            double sum = y[k];
            for (int j = k + 1; j < s.rank; ++j) sum -= L[perm[j] * M + pk] * y[j];
            y[k] = sum / L[pk * M + pk];
        }
        for (int k = 0; k < s.rank; ++k)
            alpha[s.seen[perm[k]] * C + c] = y[k] * s.scale[perm[k]];
    }
}

// k of rule 3: the kept techniques less one when n lies in their span (that
// direction is inert).
int free_coefficients(int N, const ScaledSystem& s, const int* counts) {
    std::array<bool, kMaxTechniques> kept{};
    for (int k = 0; k < s.rank; ++k) kept[s.seen[s.perm[k]]] = true;
    bool n_in_span = true;
    for (int i = 0; i < N; ++i) n_in_span = n_in_span && (counts[i] == 0 || kept[i]);
    return s.rank - (n_in_span ? 1 : 0);
}

// The pooled round variance P(λ α) of one channel (pooled_round_variance) in
// closed form for every λ, where α solves the kept block exactly:
// αᵀAα = α·b there, so P(λα) = m − (2λ − λ²) α·b − (B − λ α·ĉ)²/Σn with
// B = Σ n_i b_i (the balance estimate) and ĉ = A n. O(N) per channel.
struct ChannelFit {
    double m, alpha_b, balance, alpha_c, per_round;
    double pooled(double lambda) const {
        const double mean_z = balance - lambda * alpha_c;
        return std::max(0.0, m - (2 * lambda - lambda * lambda) * alpha_b -
                                 mean_z * mean_z / per_round);
    }
};

// Rules 3 and 4 for one channel: whether α is kept, and its shrinkage λ.
void keep_and_shrink(const ChannelFit& fit, double S, double k, bool allowed, bool& keep,
                     double& shrink) {
    keep = allowed;
    shrink = 0;
    if (keep && k > 0) {
        const double p_balance = fit.pooled(0), p_fit = fit.pooled(1);
        const double v_balance = p_balance * S / (S - 1);
        const double v_optimal = p_fit * S / (S - k - 1) * (S - 2) / (S - k - 2);
        keep = v_optimal < v_balance;
        // Rule 4: positive-part James–Stein shrinkage toward balance. The
        // fit's in-sample variance reduction overstates the true one by
        // k·σ²_res/S in expectation; the λ that minimises the variance of the
        // control variate λ·α̂ is (true gain)/(in-sample gain).
        const double in_sample_gain = p_balance - p_fit;
        const double noise = k * p_fit / (S - k - 1);
        shrink = in_sample_gain > noise ? 1.0 - noise / in_sample_gain : 0.0;
    } else if (keep) {
        shrink = 1.0;  // k = 0: α ∝ n, nothing to estimate
    }
    keep = keep && shrink > 0;
    if (!keep) shrink = 0;
}

}  // namespace

double round_variance(int N, int C, int c, const double* a, const double* b,
                      const double* m, const int* counts, const double* alpha) {
    double alpha_b = 0, alpha_a_alpha = 0, spread = 0;
    for (int i = 0; i < N; ++i) {
        double a_alpha = 0;  // (A α)_i
        for (int j = 0; j < N; ++j) a_alpha += a[i * N + j] * alpha[j * C + c];
        const double bi = b[i * C + c];
        alpha_b += alpha[i * C + c] * bi;
        alpha_a_alpha += alpha[i * C + c] * a_alpha;
        // E_i[(f − g)/q] = b_i − (A α)_i; stratification removes Σ n_i E_i².
        spread += counts[i] * (bi - a_alpha) * (bi - a_alpha);
    }
    return std::max(0.0, m[c] - 2 * alpha_b + alpha_a_alpha - spread);
}

double pooled_round_variance(int N, int C, int c, const double* a, const double* b,
                             const double* m, const int* counts, const double* alpha) {
    // (1/R) Σ Z² − ((1/R) Σ Z)² / Σn with Z = (f − g)/q, expanded in moments:
    // the sample variance of Z over one round's worth of samples.
    double alpha_b = 0, alpha_a_alpha = 0, balance = 0, alpha_c = 0, per_round = 0;
    for (int i = 0; i < N; ++i) {
        double a_alpha = 0, a_n = 0;
        for (int j = 0; j < N; ++j) {
            a_alpha += a[i * N + j] * alpha[j * C + c];
            a_n += a[i * N + j] * counts[j];  // ĉ_i
        }
        const double ai = alpha[i * C + c];
        alpha_b += ai * b[i * C + c];
        alpha_a_alpha += ai * a_alpha;
        alpha_c += ai * a_n;
        balance += counts[i] * b[i * C + c];
        per_round += counts[i];
    }
    const double mean_z = balance - alpha_c;  // (1/R) Σ Z
    return std::max(0.0, m[c] - 2 * alpha_b + alpha_a_alpha - mean_z * mean_z / per_round);
}

SolveResult solve_optimal_alpha(int N, int C, const double* a, const double* b,
                                const double* m, const int* counts,
                                double total_samples, double min_samples_per_coefficient) {
    SolveResult result;
    std::fill(result.alpha.begin(), result.alpha.begin() + std::min(N * C, int(result.alpha.size())),
              0.0);
    if (N > kMaxTechniques || C > kMaxChannels) return result;

    ScaledSystem system;
    scale_seen(N, C, a, b, system);
    if (system.M == 0) return result;
    pivoted_cholesky(system);
    result.rank = system.rank;
    if (system.rank == 0) return result;
    substitute(C, system, result.alpha.data());

    // Rules 3 and 4 per channel (see solver.h), from the closed form of the
    // pooled variance: ĉ = A n once, then O(N) per channel.
    const double k = free_coefficients(N, system, counts);
    const double S = total_samples;
    result.free_coefficients = int(k);
    std::array<double, kMaxTechniques> c_hat;
    double per_round = 0;
    for (int i = 0; i < N; ++i) {
        double sum = 0;
        for (int j = 0; j < N; ++j) sum += a[i * N + j] * counts[j];
        c_hat[i] = sum;
        per_round += counts[i];
    }
    const bool enough = S > k + 2 && S >= min_samples_per_coefficient * (k + 1);
    for (int c = 0; c < C; ++c) {
        ChannelFit fit{m[c], 0, 0, 0, per_round};
        bool finite = true;
        for (int i = 0; i < N; ++i) {
            const double ai = result.alpha[i * C + c];
            finite = finite && std::isfinite(ai);
            fit.alpha_b += ai * b[i * C + c];
            fit.alpha_c += ai * c_hat[i];
            fit.balance += counts[i] * b[i * C + c];
        }
        bool keep;
        double shrink;
        keep_and_shrink(fit, S, k, enough && finite, keep, shrink);
        result.kept[c] = keep;
        result.shrink[c] = shrink;
        for (int i = 0; i < N; ++i) result.alpha[i * C + c] *= shrink;
        // The residual variance at the final α, for the caller's error bar.
        result.fit_variance[c] = keep ? fit.pooled(shrink) : 0.0;
    }
    return result;
}

}  // namespace omis
