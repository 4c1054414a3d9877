#include "render/receiver.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace omis {
namespace {

// Schlick's Fresnel weight (1 − u)⁵, u clamped as Cycles' schlick_fresnel.
double schlick_weight(double u) {
    const double m = std::clamp(1.0 - u, 0.0, 1.0);
    const double m2 = m * m;
    return m2 * m2 * m;
}

// Oren–Nayar's A, B for σ ∈ [0, 1] (Cycles' "simplified" qualitative model).
void oren_nayar_ab(double sigma, double& a, double& b) {
    const double s = std::clamp(sigma, 0.0, 1.0);
    const double div = 1.0 / (kPi + ((3.0 * kPi - 4.0) / 6.0) * s);
    a = div;
    b = s * div;
}

}  // namespace

double Receiver::lambert_ratio(double cos_theta) const {
    switch (model) {
        case ReceiverModel::Lambert: return 1.0;
        case ReceiverModel::PrincipledDiffuse: {
            const double f = schlick_weight(cos_theta);
            return 1.0 - 0.5 * f + roughness * (1.0 + cos_theta) * f;
        }
        case ReceiverModel::OrenNayar: {
            double a, b;
            oren_nayar_ab(roughness, a, b);
            return kPi * a;
        }
    }
    return 1.0;
}

// With μ = cosθ, ∫_H (μ/π) ratio(μ) dω = 2 ∫_0^1 μ ratio(μ) dμ. Principled:
// 2 ∫ μ (1 − F/2 + r (1 + μ) F) dμ, F = (1 − μ)⁵, by the Beta integrals
// ∫ μ (1 − μ)⁵ = 1/42 and ∫ μ² (1 − μ)⁵ = 1/168: 1 − 1/42 + r·5/84.
double Receiver::hemisphere_integral() const {
    switch (model) {
        case ReceiverModel::Lambert: return 1.0;
        case ReceiverModel::PrincipledDiffuse: return 1.0 - 1.0 / 42.0 + roughness * 5.0 / 84.0;
        case ReceiverModel::OrenNayar: return lambert_ratio(1.0);  // a constant ratio
    }
    return 1.0;
}

std::string Receiver::name() const {
    std::ostringstream s;
    switch (model) {
        case ReceiverModel::Lambert: return "lambert";
        case ReceiverModel::PrincipledDiffuse: s << "principled(" << roughness << ")"; break;
        case ReceiverModel::OrenNayar: s << "oren-nayar(" << roughness << ")"; break;
    }
    return s.str();
}

Receiver make_receiver(ReceiverModel model, double roughness) {
    if (model != ReceiverModel::Lambert && model != ReceiverModel::PrincipledDiffuse &&
        model != ReceiverModel::OrenNayar)
        throw std::invalid_argument("model: unknown receiver model " +
                                    std::to_string(int(model)));
    if (!std::isfinite(roughness) || roughness < 0)
        throw std::invalid_argument("roughness: must be a finite number ≥ 0");
    Receiver r;
    r.model = model;
    r.roughness = model == ReceiverModel::Lambert ? 0.0 : roughness;
    // Cycles' Diffuse BSDF with roughness 0 is its Lambert closure.
    if (model == ReceiverModel::OrenNayar && roughness == 0) r.model = ReceiverModel::Lambert;
    return r;
}

double principled_diffuse_closure(const Vec3& n, const Vec3& v, const Vec3& l,
                                  double roughness) {
    const double nl = dot(n, l);
    if (!(nl > 0)) return 0.0;
    const double fv = schlick_weight(dot(n, v)), fl = schlick_weight(nl);
    // Burley's diffuse, split as Cycles does into a Lambert-like part and
    // retro-reflection (rr = roughness · 2 cos²θ_h = roughness (L·V + 1)).
    const double rr = roughness * (dot(l, v) + 1.0);
    const double f = (1.0 - 0.5 * fv) * (1.0 - 0.5 * fl) + rr * (fl + fv + fl * fv * (rr - 1.0));
    return kInvPi * nl * f;
}

double oren_nayar_closure(const Vec3& n, const Vec3& v, const Vec3& l, double sigma) {
    const double nl = std::max(dot(n, l), 0.0), nv = std::max(dot(n, v), 0.0);
    if (!(nl > 0)) return 0.0;
    double t = dot(l, v) - nl * nv;
    if (t > 0) t /= std::max(nl, nv);
    double a, b;
    oren_nayar_ab(sigma, a, b);
    return nl * (a + b * t);
}

}  // namespace omis
