// Shading points for vertex-colour bakes, placed as Cycles 3.4 places them.
//
// Cycles bakes a colour attribute per face corner: the corner's pixel sits on
// the first triangle holding it, exactly at the vertex (object_bake_api.cc,
// bake_targets_populate_pixels_color_attributes), and the kernel then nudges a
// point lying exactly on a vertex towards the triangle's centre "to avoid
// self-intersection" (init_from_bake.h, bake_offset_towards_center): by
// min(|c − p|, max(‖p‖∞, 1) · 1e-4) along c − p, barycentrics then clamped to
// [1e-5, 1 − 1e-5]. A vertex value is the mean of its corners' values.
//
// The nudge is what lights a floor's vertex where a wall stands on it: the
// vertex itself lies on the wall's surface, where rays toward the open side
// start inside the wall's plane and hit it; the nudged point lies off it.
#pragma once

#include <cstdint>

#include "bake/bake.h"
#include "scene/geometry_scene.h"

namespace omis {

// Barycentrics (of vertices 1 and 2) of corner k (0, 1, 2) of triangle t, moved
// towards the triangle's centre as Cycles' bake does. A degenerate triangle
// keeps the corner (Cycles returns barycentrics (0, 0) there).
struct CornerPoint {
    double b1 = 0, b2 = 0;
};
CornerPoint inset_corner(const Mesh& mesh, std::uint32_t t, int k);

// A Vertices bake from a Corners bake of the same mesh: each vertex takes the
// mean of its corners (as Cycles' POINT-domain colour attributes do); its
// noise combines the corners' variances as for a mean of independent values.
BakeResult corners_to_vertices(const Mesh& mesh, BakeResult corners);

}  // namespace omis
