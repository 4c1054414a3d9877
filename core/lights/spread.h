// Blender's spread profile and the constants a spread light keeps (internal
// to lights/: light.cpp evaluates the falloff, light_factories.cpp makes the
// constants with the light).
#pragma once

#include <algorithm>
#include <cmath>

#include "lights/light.h"

namespace omis {

// Blender's spread (SPEC §4): radiance × max(0, 1 − tan a tan θ) × normalisation,
// a = (π − s)/2. The normalisation 2/(2 + (2a − π) tan a) equals 1/(1 − b cot b)
// with b = s/2, evaluated by its series where it would cancel. The two
// constants are the light's (Light::spread_constants, made with it).
struct SpreadProfile {
    double tan_a = 0, one_minus_b_cot_b = 1;
    explicit SpreadProfile(double spread) {
        const double b = 0.5 * spread;
        one_minus_b_cot_b = b < 1e-3 ? b * b / 3 + b * b * b * b / 45 : 1 - b / std::tan(b);
        tan_a = 1.0 / std::tan(b);  // tan((π − s)/2) = cot(s/2)
    }
    explicit SpreadProfile(const Light::SpreadConstants& k)
        : tan_a(k.cot_half), one_minus_b_cot_b(k.one_minus_b_cot_b) {}
    double factor(double cos_theta) const {
        const double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
        const double tan_theta = sin_theta / std::max(cos_theta, 1e-300);
        return std::max(0.0, 1 - tan_a * tan_theta) / one_minus_b_cot_b;
    }
};

// The constants spread_box and the falloff take for a light spanned by e1, e2
// (the same arithmetic as computing them at every call, once).
inline Light::SpreadConstants spread_constants(double spread, const Vec3& e1, const Vec3& e2) {
    Light::SpreadConstants k;
    const double b = 0.5 * spread;
    const SpreadProfile profile(spread);
    k.tan_half = std::tan(b);
    k.cot_half = profile.tan_a;
    k.one_minus_b_cot_b = profile.one_minus_b_cot_b;
    k.unit_normal = normalize(cross(e1, e2));
    k.length1 = std::sqrt(dot(e1, e1));
    k.length2 = std::sqrt(dot(e2, e2));
    return k;
}

}  // namespace omis
