#include "mis/solver.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace omis {
namespace {

// Numerical rank threshold on unit-diagonal pivots (see solver.h, rule 3).
constexpr double kPivotThreshold = 1e-10;
constexpr int kMaxTechniques = kMaxSolveTechniques;
constexpr int kMaxChannels = kMaxSolveChannels;

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
    if (N > kMaxTechniques || C > kMaxChannels) return result;  // rule 2

    // Rule 1 and the unit-diagonal scaling: work on the techniques that were seen.
    std::array<int, kMaxTechniques> seen{};
    std::array<double, kMaxTechniques> scale{};
    int M = 0;
    for (int i = 0; i < N; ++i) {
        const double d = a[i * N + i];
        if (d > 0 && std::isfinite(d)) {
            seen[M] = i;
            scale[M] = 1.0 / std::sqrt(d);
            ++M;
        }
    }
    if (M == 0) return result;

    // Scaled copy S = D A D (unit diagonal) and right-hand sides D b.
    // Left uninitialised on purpose: only the M×M block is used, and clearing
    // 8 KB per solve would dominate its cost.
    std::array<double, kMaxTechniques * kMaxTechniques> L;
    std::array<double, kMaxTechniques * kMaxChannels> rhs;
    for (int i = 0; i < M; ++i) {
        for (int j = 0; j < M; ++j)
            L[i * M + j] = a[seen[i] * N + seen[j]] * scale[i] * scale[j];
        for (int c = 0; c < C; ++c) rhs[i * C + c] = b[seen[i] * C + c] * scale[i];
    }

    // Rule 3: Cholesky with diagonal pivoting, in place (lower triangle), stopping
    // at the first pivot below the threshold.
    std::array<int, kMaxTechniques> perm{};
    for (int i = 0; i < M; ++i) perm[i] = i;
    int rank = 0;
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
        ++rank;
    }
    result.rank = rank;
    if (rank == 0) return result;

    // Forward and back substitution over the pivoted block, per channel.
    std::array<double, kMaxTechniques> y{};
    for (int c = 0; c < C; ++c) {
        for (int k = 0; k < rank; ++k) {
            const int pk = perm[k];
            double s = rhs[pk * C + c];
            for (int j = 0; j < k; ++j) s -= L[pk * M + perm[j]] * y[j];
            y[k] = s / L[pk * M + pk];
        }
        for (int k = rank - 1; k >= 0; --k) {
            const int pk = perm[k];
            double s = y[k];
            for (int j = k + 1; j < rank; ++j) s -= L[perm[j] * M + pk] * y[j];
            y[k] = s / L[pk * M + pk];
        }
        for (int k = 0; k < rank; ++k) {
            const int pk = perm[k];
            result.alpha[seen[pk] * C + c] = y[k] * scale[pk];
        }
    }

    bool n_in_span = true;
    std::array<bool, kMaxTechniques> kept{};
    for (int k = 0; k < rank; ++k) kept[seen[perm[k]]] = true;
    for (int i = 0; i < N; ++i) n_in_span = n_in_span && (counts[i] == 0 || kept[i]);

    // Rule 3: keep α only if it is predicted to beat the balance heuristic once
    // the cost of estimating it is paid (see solver.h).
    const double k = rank - (n_in_span ? 1 : 0);  // free coefficients
    const double S = total_samples;
    result.free_coefficients = int(k);
    static constexpr std::array<double, kMaxTechniques * kMaxChannels> zero{};
    for (int c = 0; c < C; ++c) {
        bool keep = S > k + 2 && S >= min_samples_per_coefficient * (k + 1);
        for (int i = 0; i < N; ++i) keep = keep && std::isfinite(result.alpha[i * C + c]);
        double shrink = 0, p_fit = 0;
        if (keep && k > 0) {
            const double p_balance = pooled_round_variance(N, C, c, a, b, m, counts, zero.data());
            p_fit = pooled_round_variance(N, C, c, a, b, m, counts, result.alpha.data());
            const double v_balance = p_balance * S / (S - 1);
            const double v_optimal = p_fit * S / (S - k - 1) * (S - 2) / (S - k - 2);
            keep = v_optimal < v_balance;
            // Rule 4: positive-part James–Stein shrinkage toward balance.
            // The fit's in-sample variance reduction overstates the true one
            // by k·σ²_res/S in expectation; the λ that minimises the variance
            // of the control variate λ·α̂ is (true gain)/(in-sample gain).
            const double in_sample_gain = p_balance - p_fit;
            const double noise = k * p_fit / (S - k - 1);
            shrink = in_sample_gain > noise ? 1.0 - noise / in_sample_gain : 0.0;
        } else if (keep) {
            shrink = 1.0;  // k = 0: α ∝ n, nothing to estimate
        }
        keep = keep && shrink > 0;
        result.kept[c] = keep;
        result.shrink[c] = keep ? shrink : 0.0;
        for (int i = 0; i < N; ++i) result.alpha[i * C + c] *= result.shrink[c];
        // The residual variance at the final α, for the caller's error bar
        // (computed here so that it is computed once).
        result.fit_variance[c] =
            keep && k > 0 && shrink == 1.0
                ? p_fit
                : keep ? pooled_round_variance(N, C, c, a, b, m, counts, result.alpha.data())
                       : 0.0;
    }
    return result;
}

}  // namespace omis
