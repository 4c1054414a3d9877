// Where a receiver mesh lies on other meshes' surfaces, and whether a point
// of it lies inside other geometry (issue 32).
//
// Cycles starts a shadow ray on the shading point itself and skips only the
// triangle it starts on, so a point that also lies on another object's face
// (two crates of one height side by side: their tops are coplanar where they
// overlap) has every ray stopped at once by that face. omis' rays leave from
// an origin offset off the receiver by its float error bound
// (scene/ray_offset.h), which steps past such a face: those points were lit.
// SurfaceContacts finds, per receiver triangle, the other meshes' triangles
// that are parallel to it and pass within that bound of it (most triangles
// have none: the test then costs nothing), and tells whether a point lies on
// one of them.
#pragma once

#include <cstdint>
#include <vector>

#include "math/vec3.h"
#include "scene/geometry_scene.h"

namespace omis {

class SurfaceContacts {
public:
    // The contacts of mesh `receiver` in a committed scene.
    SurfaceContacts(const GeometryScene& geometry, std::uint32_t receiver);

    // Whether point x of the receiver's triangle `triangle` lies on another
    // mesh's surface: within contact_distance(x) of the plane of one of that
    // triangle's contacts, inside it. Facing: a face turned the receiver's
    // way (the two surfaces coincide there: z-fighting); Touching: only
    // faces turned against it (a crate resting on a floor).
    enum class Contact { None, Touching, Facing };
    Contact on_other_surface(std::uint32_t triangle, const Vec3& x) const;
    bool any() const { return !partners_.empty(); }
    // Whether x lies in the bounding box of some other mesh (grown by the
    // contact distance): elsewhere it cannot be inside other geometry.
    bool may_be_inside(const Vec3& x) const;
    // Receiver triangles with at least one contact (for tests).
    std::size_t triangles_in_contact() const;

    // How far from another surface a point counts as on it: four times the
    // float error bound the ray offset steps over (ray_offset.h, point_error),
    // so that every surface the offset could carry an origin past is found.
    static double contact_distance(const Vec3& x);

    // Where a point on another surface has its rays leave from (as
    // SurfacePoint::x): moved behind both faces along the receiver's normal
    // ng (oriented to the shading normal n) by three contact distances, so
    // that the ray offset (one error bound toward the ray) leaves the origin
    // behind them and every ray toward n's side crosses them, as Cycles'
    // rays from the point itself do.
    static Vec3 behind_contact(const Vec3& x, const Vec3& n, const Vec3& ng);

private:
    struct Partner {
        Vec3 a, e1, e2;       // triangle a + s·e1 + t·e2, s, t ≥ 0, s + t ≤ 1
        Vec3 normal;          // unit
    };
    const GeometryScene& geometry_;
    std::uint32_t receiver_;
    // Per receiver triangle: its first partner in partners_ and how many.
    std::vector<std::uint32_t> first_, count_;
    std::vector<Partner> partners_;
    std::vector<std::pair<Vec3, Vec3>> other_boxes_;  // other meshes' bounds (lo, hi)
};

// Whether point p (normal n, geometric normal ng) lies inside other geometry:
// a ray along n meets the back of a surface first, and so do most of four
// more rays tilted 60° from n around it. A point in the open or in a room
// (its ceiling's inner side faces it) costs one ray; a point inside a closed
// object five. Each ray is counted in the scene's rays_traced.
bool inside_other_geometry(const GeometryScene& geometry, const Vec3& p, const Vec3& n,
                           const Vec3& ng);

}  // namespace omis
