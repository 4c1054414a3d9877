#include "sampling/irradiance.h"

#include <cmath>

#include "math/vec3.h"

namespace omis {

double polygon_irradiance(const Vec3& x, const Vec3& n, const std::vector<Vec3>& vertices) {
    const size_t m = vertices.size();
    if (m < 3) return 0;
    // Sutherland–Hodgman against the half-space (p − x)·n ≥ 0, in offsets from x.
    std::vector<Vec3> p;
    p.reserve(m + 2);
    for (size_t i = 0; i < m; ++i) {
        const Vec3 a = vertices[i] - x, b = vertices[(i + 1) % m] - x;
        const double da = dot(a, n), db = dot(b, n);
        if (da >= 0) p.push_back(a);
        if ((da >= 0) != (db >= 0)) p.push_back(a + (b - a) * (da / (da - db)));
    }
    if (p.size() < 3) return 0;
    double sum = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        const Vec3& a = p[i];
        const Vec3& b = p[(i + 1) % p.size()];
        const Vec3 c = cross(a, b - a);  // = a × b, formed with the short edge
        const double lc = length(c);
        if (!(lc > 0)) continue;
        sum += std::atan2(lc, dot(a, b)) * dot(n, c) / lc;
    }
    return 0.5 * std::abs(sum);
}

double ellipse_irradiance(const Vec3& x, const Vec3& n, const Vec3& center,
                          const Vec3& axis_a, const Vec3& axis_b, int segments) {
    const double step = 2.0 * kPi / segments;
    // Scale so that the polygon's area equals the ellipse's.
    const double k = std::sqrt(step / std::sin(step));
    std::vector<Vec3> v(segments);
    for (int i = 0; i < segments; ++i)
        v[i] = center + (axis_a * std::cos(i * step) + axis_b * std::sin(i * step)) * k;
    return polygon_irradiance(x, n, v);
}

bool is_in_front(const Vec3& x, const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v) {
    return dot(x - corner, cross(edge_u, edge_v)) > 0;
}

}  // namespace omis
