// Unoccluded irradiance from constant-radiance emitters (SPEC §5): exact answers for
// tests and the `unoccluded` light selection. Results are E/L (sr·cos-weighted).
#pragma once

#include <vector>

#include "math/vec3.h"

namespace omis {

// Lambert's formula for a convex planar polygon (any vertex count ≥ 3, either winding),
// clipped to the receiver's horizon first; θ_e via atan2. Both sides emit: callers with
// one-sided lights check is_in_front() first. Returns ≥ 0.
double polygon_irradiance(const Vec3& x, const Vec3& n, const std::vector<Vec3>& vertices);

// Disk/ellipse center + cos·axis_a + sin·axis_b through an equal-area polygon with
// `segments` vertices. The area is exact; the shape error is O(segments⁻²): with 256
// segments the relative error is below 1e-5 for a coaxial disk at any distance and
// below 1e-4 in the tests' grazing and straddling configurations.
double ellipse_irradiance(const Vec3& x, const Vec3& n, const Vec3& center,
                          const Vec3& axis_a, const Vec3& axis_b, int segments = 256);

// Whether x sees the emitting side of a one-sided planar light that emits toward
// cross(edge_u, edge_v) (rect edges, or p1 − p0 and p2 − p0 of a triangle).
bool is_in_front(const Vec3& x, const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v);

}  // namespace omis
