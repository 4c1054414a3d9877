// The receiver's own diffuse closure, evaluated as Cycles 3.4's Diffuse bake
// sees it (SPEC §3): the bake starts its path with a ray travelling along -N
// (init_from_bake.h), so the outgoing (view) direction is the shading normal n
// itself, and the Diffuse "Direct" pass is divided by the closure's colour
// (the DiffCol pass). What remains multiplies the incident radiance:
//
//   Lambert              cosθ/π                                  (bsdf_diffuse.h)
//   PrincipledDiffuse r  cosθ/π · (1 − F/2 + r(1 + cosθ) F),    F = (1 − cosθ)⁵
//                        (bsdf_principled_diffuse.h with V = N: F_V = 0, L·V + 1 = 1 + cosθ)
//   OrenNayar σ          cosθ · 1/(π + (3π − 4)/6 · σ),         σ clamped to [0, 1]
//                        (bsdf_oren_nayar.h with V = N: t = L·V − (N·L)(N·V) = 0)
//
// θ is the angle between n and the incoming direction. Each is a bounded
// multiple of Lambert's cosθ/π (principled: between 1/2 and 1 + 2r; Oren–Nayar:
// a constant ≤ 1), so the cosine-weighted `bsdf` technique stays a good
// importance sampler for every model and keeps its pdf.
#pragma once

#include <string>

#include "math/vec3.h"

namespace omis {

enum class ReceiverModel { Lambert = 0, PrincipledDiffuse = 1, OrenNayar = 2 };

struct Receiver {
    ReceiverModel model = ReceiverModel::Lambert;
    double roughness = 0;  // Principled "Roughness" or Diffuse BSDF "Roughness" (σ)

    bool is_lambert() const { return model == ReceiverModel::Lambert; }
    // The closure relative to Lambert's cosθ/π at cos_theta ∈ (0, 1].
    double lambert_ratio(double cos_theta) const;
    // ∫ over the hemisphere of the closure (receiver_cosine_factor) dω, what a
    // constant radiance of 1 from every direction gives (Lambert: 1).
    double hemisphere_integral() const;
    std::string name() const;  // "lambert", "principled(0.5)", "oren-nayar(1)"
};

// Throws std::invalid_argument naming `roughness` when it is negative or not
// finite (Cycles clamps Oren–Nayar's σ to [0, 1]; the principled diffuse takes
// any roughness ≥ 0).
Receiver make_receiver(ReceiverModel model, double roughness);

// The factor that replaces cosθ/π in the integrand (and multiplies E/π of
// delta lights as lambert_ratio). Lambert is the inline fast path.
inline double receiver_cosine_factor(const Receiver& r, double cos_theta) {
    if (r.is_lambert()) return cos_theta * kInvPi;
    return cos_theta * kInvPi * r.lambert_ratio(cos_theta);
}

// The general closures (any view direction v), as Cycles 3.4 evaluates them
// times N·L, for unit n, v, l; 0 below the horizon. For tests and reference.
double principled_diffuse_closure(const Vec3& n, const Vec3& v, const Vec3& l, double roughness);
double oren_nayar_closure(const Vec3& n, const Vec3& v, const Vec3& l, double sigma);

}  // namespace omis
