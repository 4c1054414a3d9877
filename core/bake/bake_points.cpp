#include "bake/bake_points.h"

#include "bake/vertex_points.h"

namespace omis::bake_detail {

SurfacePoint on_contact(SurfacePoint p, std::uint32_t t, const SurfaceContacts* contacts) {
    if (contacts && contacts->on_other_surface(t, p.x) != SurfaceContacts::Contact::None)
        p.x = SurfaceContacts::behind_contact(p.x, p.n, p.ng);
    return p;
}

std::vector<SurfacePoint> corner_points(const Mesh& mesh, bool smooth) {
    std::vector<SurfacePoint> points;
    for (std::uint32_t t = 0; t < mesh.num_triangles(); ++t)
        for (int k = 0; k < 3; ++k) {
            const Vec3 ng = mesh.geometric_normal(t);
            const CornerPoint c = inset_corner(mesh, t, k);
            Vec3 n = smooth ? mesh.shading_normal(t, c.b1, c.b2) : ng;
            if (!(length(n) > 0)) n = ng;
            points.push_back({mesh.position(t, c.b1, c.b2), n, ng});
        }
    return points;
}

}  // namespace omis::bake_detail
