#include "sampling/projected.h"

#include <algorithm>
#include <cmath>

namespace omis {
namespace {

// Ωp of the spherical triangle a b c (unit vectors) about n: Lambert's formula.
double lambert_triangle(const Vec3& n, const Vec3& a, const Vec3& b, const Vec3& c) {
    auto edge = [&](const Vec3& p, const Vec3& q) {
        const Vec3 x = cross(p, q);
        const double s = length(x);
        return s > 0 ? std::atan2(s, dot(p, q)) * dot(n, x) / s : 0.0;
    };
    return 0.5 * std::abs(edge(a, b) + edge(b, c) + edge(c, a));
}

// ∫₀^S sin² s ds = S/2 − sin(2S)/4, by its series where that cancels.
double sin2_integral(double S) {
    if (S < 1e-2) {
        const double s2 = S * S;
        return S * s2 * (1.0 / 3 - s2 * (1.0 / 15 - s2 * (2.0 / 315)));
    }
    return 0.5 * S - 0.25 * std::sin(2 * S);
}

// Solves F(t) = target on [lo, hi] for nondecreasing F with derivative dF, from t.
template <class F, class D>
double newton_bracketed(F&& f, D&& df, double target, double lo, double hi, double t) {
    const double width = hi - lo;
    for (int it = 0; it < 60; ++it) {
        const double r = f(t) - target;
        if (r > 0) hi = t;
        else lo = t;
        const double d = df(t);
        double next = d > 0 ? t - r / d : 0.5 * (lo + hi);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        // 1e-11 of the bracket: far below any visible bias, and above the rounding
        // noise of Lambert's sum, which would keep Newton stepping.
        const bool done = std::abs(next - t) <= 1e-11 * width || hi - lo <= 1e-11 * width;
        t = next;
        if (done) break;
    }
    return t;
}

}  // namespace

std::optional<ProjectedPolygon> ProjectedPolygon::make(const Vec3& n, const Vec3& to_first,
                                                       const std::array<Vec3, 4>& offsets,
                                                       int count) {
    ProjectedPolygon p;
    p.n_ = n;
    p.plane_point_ = to_first;
    p.plane_normal_ = cross(offsets[1] - offsets[0], offsets[2] - offsets[0]);
    // Clip at the horizon plane n·v = 0 (Sutherland–Hodgman, one plane).
    std::array<Vec3, 5> clipped;
    int k = 0;
    for (int i = 0; i < count; ++i) {
        const Vec3 a = to_first + offsets[i], b = to_first + offsets[(i + 1) % count];
        const double da = dot(n, a), db = dot(n, b);
        if (da >= 0) clipped[k++] = a;
        if ((da > 0 && db < 0) || (da < 0 && db > 0)) {
            const double t = da / (da - db);
            clipped[k++] = a + (b - a) * t;
        }
    }
    if (k < 3) return std::nullopt;
    for (int i = 0; i < k; ++i) p.dirs_[i] = normalize(clipped[i]);
    double running = 0;
    for (int i = 0; i + 2 < k; ++i) {
        running += lambert_triangle(n, p.dirs_[0], p.dirs_[i + 1], p.dirs_[i + 2]);
        p.cdf_[i] = running;
    }
    p.triangles_ = k - 2;
    p.total_ = running;
    if (!(p.total_ > 0) || !std::isfinite(p.total_)) return std::nullopt;
    return p;
}

Vec3 ProjectedPolygon::sample_triangle(int i, double u1, double u2) const {
    const Vec3 &A = dirs_[0], &B = dirs_[i + 1], &C = dirs_[i + 2];
    // Tangent frame at A: u(ψ) = uB cos ψ + t2 sin ψ, ψ from B's side to C's.
    const Vec3 uB = normalize(B - A * dot(A, B));
    const Vec3 cC = C - A * dot(A, C);
    const Vec3 t2 = normalize(cC - uB * dot(uB, cC));
    const double psi_c = std::atan2(dot(cC, t2), dot(cC, uB));
    const Vec3 m = cross(B, C);  // the opposite edge's great circle
    const double pm = dot(A, m), sign = pm > 0 ? 1.0 : -1.0, a = dot(n_, A);
    auto tangent = [&](double psi) { return uB * std::cos(psi) + t2 * std::sin(psi); };
    auto s_max = [&](double psi) {  // where the arc from A along u(ψ) meets B C
        return std::atan2(std::abs(pm), -sign * dot(tangent(psi), m));
    };
    auto edge_point = [&](double psi) {
        const double s = s_max(psi);
        return A * std::cos(s) + tangent(psi) * std::sin(s);
    };
    const double total = lambert_triangle(n_, A, B, C);
    auto phi = [&](double psi) { return psi <= 0 ? 0.0 : lambert_triangle(n_, A, B, edge_point(psi)); };
    auto inner = [&](double psi) {  // ∫₀^smax cos θ sin s ds = dΦ/dψ
        const double S = s_max(psi), sS = std::sin(S);
        return a * 0.5 * sS * sS + dot(n_, tangent(psi)) * sin2_integral(S);
    };
    const double psi = newton_bracketed(phi, inner, u1 * total, 0.0, psi_c, u1 * psi_c);
    const Vec3 u = tangent(psi);
    const double b = dot(n_, u), S = s_max(psi);
    auto G = [&](double s) { const double ss = std::sin(s); return a * 0.5 * ss * ss + b * sin2_integral(s); };
    auto g = [&](double s) { return std::max(0.0, (a * std::cos(s) + b * std::sin(s)) * std::sin(s)); };
    const double s = newton_bracketed(G, g, u2 * G(S), 0.0, S, S * std::sqrt(u2));
    return normalize(A * std::cos(s) + u * std::sin(s));
}

DirSample ProjectedPolygon::sample(double u1, double u2) const {
    const double target = u1 * total_;
    int i = 0;
    while (i + 1 < triangles_ && cdf_[i] < target) ++i;
    const double below = i > 0 ? cdf_[i - 1] : 0.0, share = cdf_[i] - below;
    const double v1 = share > 0 ? std::clamp((target - below) / share, 0.0, 1.0) : 0.5;
    const Vec3 w = sample_triangle(i, v1, u2);
    const double den = dot(w, plane_normal_);
    const double t = den != 0 ? dot(plane_point_, plane_normal_) / den : 0.0;
    return {w, t > 0 && std::isfinite(t) ? t : length(plane_point_)};
}

}  // namespace omis
