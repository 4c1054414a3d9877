#include "scene/surface_contacts.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "scene/ray_offset.h"

namespace omis {

namespace {

// Planes at most this far from parallel (1 − cos of the angle) can hold a
// contact wider than a rounding strip: a float-rounded copy of a tilted
// plane stays within ~1e-7 of it; two planes crossing at a larger angle meet
// along a line, which no sample lands on.
constexpr double kParallel = 1e-6;

struct Candidates {
    std::uint32_t receiver = 0, meshes = 0;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> found;  // (mesh, triangle)
};

// Embree's point query: every primitive whose bounds meet the sphere.
bool collect(RTCPointQueryFunctionArguments* args) {
    auto* c = static_cast<Candidates*>(args->userPtr);
    if (args->geomID < c->meshes && args->geomID != c->receiver)
        c->found.emplace_back(args->geomID, args->primID);
    return false;  // the radius stays: every candidate is wanted
}

// The largest |coordinate| of a triangle: the scale its rounding has.
double scale_of(const std::array<Vec3, 3>& v) {
    double s = 0;
    for (const Vec3& p : v) s = std::max({s, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    return s;
}

}  // namespace

double SurfaceContacts::contact_distance(const Vec3& x) {
    return 4.0 * point_error(x).x;
}

Vec3 SurfaceContacts::behind_contact(const Vec3& x, const Vec3& n, const Vec3& ng) {
    const double len = length(ng);
    if (!(len > 0)) return x;
    const Vec3 side = dot(ng, n) < 0 ? -ng / len : ng / len;
    return x - 3.0 * contact_distance(x) * side;
}

SurfaceContacts::SurfaceContacts(const GeometryScene& geometry, std::uint32_t receiver)
    : geometry_(geometry), receiver_(receiver) {
    const Mesh& mesh = geometry.mesh(receiver);
    first_.assign(mesh.num_triangles(), 0);
    count_.assign(mesh.num_triangles(), 0);
    if (geometry.num_meshes() < 2) return;
    for (std::uint32_t m = 0; m < geometry.num_meshes(); ++m) {
        if (m == receiver) continue;
        const Mesh& other = geometry.mesh(m);
        Vec3 lo = other.positions[0], hi = lo;
        for (const Vec3& p : other.positions) {
            lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
            hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        }
        other_boxes_.emplace_back(lo, hi);
    }
    Candidates c;
    c.receiver = receiver;
    c.meshes = std::uint32_t(geometry.num_meshes());
    for (std::uint32_t t = 0; t < mesh.num_triangles(); ++t) {
        const auto v = mesh.triangle_vertices(t);
        const Vec3 normal = mesh.geometric_normal(t);
        if (!(length(normal) > 0)) continue;
        // The triangle's bounding sphere, grown by the contact distance.
        const Vec3 centre = (v[0] + v[1] + v[2]) / 3.0;
        double radius = 0;
        for (const Vec3& p : v) radius = std::max(radius, length(p - centre));
        const double tolerance = 4.0 * point_error(Vec3{scale_of(v), 0, 0}).x;
        RTCPointQuery query;
        query.x = float(centre.x);
        query.y = float(centre.y);
        query.z = float(centre.z);
        query.radius = float(radius * (1 + 1e-6) + 2 * tolerance);
        query.time = 0;
        RTCPointQueryContext context;
        rtcInitPointQueryContext(&context);
        c.found.clear();
        rtcPointQuery(geometry.handle(), &query, &context, collect, &c);
        first_[t] = std::uint32_t(partners_.size());
        for (const auto& [m, other] : c.found) {
            const Mesh& om = geometry.mesh(m);
            const Vec3 on = om.geometric_normal(other);
            if (!(length(on) > 0) || 1.0 - std::abs(dot(on, normal)) > kParallel) continue;
            const auto w = om.triangle_vertices(other);
            // Parallel planes: the receiver's vertices' distance to the other's.
            const double gap = std::abs(dot(v[0] - w[0], on));
            if (gap > tolerance + 4.0 * point_error(Vec3{scale_of(w), 0, 0}).x) continue;
            partners_.push_back({w[0], w[1] - w[0], w[2] - w[0], on});
        }
        count_[t] = std::uint32_t(partners_.size()) - first_[t];
    }
    if (partners_.empty()) first_.clear(), count_.clear();
}

bool SurfaceContacts::may_be_inside(const Vec3& x) const {
    const double e = contact_distance(x);
    for (const auto& [lo, hi] : other_boxes_)
        if (x.x >= lo.x - e && x.x <= hi.x + e && x.y >= lo.y - e && x.y <= hi.y + e &&
            x.z >= lo.z - e && x.z <= hi.z + e)
            return true;
    return false;
}

std::size_t SurfaceContacts::triangles_in_contact() const {
    return std::size_t(std::count_if(count_.begin(), count_.end(),
                                     [](std::uint32_t c) { return c > 0; }));
}

SurfaceContacts::Contact SurfaceContacts::on_other_surface(std::uint32_t triangle,
                                                           const Vec3& x) const {
    if (partners_.empty() || triangle >= count_.size() || count_[triangle] == 0)
        return Contact::None;
    const Vec3 own = geometry_.mesh(receiver_).geometric_normal(triangle);
    const double near = contact_distance(x);
    Contact found = Contact::None;
    for (std::uint32_t i = first_[triangle]; i < first_[triangle] + count_[triangle]; ++i) {
        const Partner& p = partners_[i];
        const Vec3 d = x - p.a;
        if (std::abs(dot(d, p.normal)) > near) continue;
        // Barycentrics of x's projection (Cramer's rule in the plane).
        const double e11 = dot(p.e1, p.e1), e12 = dot(p.e1, p.e2), e22 = dot(p.e2, p.e2);
        const double d1 = dot(d, p.e1), d2 = dot(d, p.e2);
        const double det = e11 * e22 - e12 * e12;
        if (!(det > 0)) continue;
        const double s = (e22 * d1 - e12 * d2) / det, t = (e11 * d2 - e12 * d1) / det;
        if (s < 0 || t < 0 || s + t > 1) continue;
        if (dot(p.normal, own) > 0) return Contact::Facing;
        found = Contact::Touching;
    }
    return found;
}

bool inside_other_geometry(const GeometryScene& geometry, const Vec3& p, const Vec3& n,
                           const Vec3& ng) {
    const Frame frame(n);
    auto back_face = [&](const Vec3& w) {
        const auto hit = geometry.intersect(offset_ray_origin(p, ng, w), w, 0,
                                            std::numeric_limits<double>::infinity());
        return hit && dot(hit->geometric_normal, w) > 0;
    };
    if (!back_face(n)) return false;
    // Four more at 60° from n, a quarter turn apart: inside when at least
    // two of them (three of the five) meet a back face first.
    const double s = std::sqrt(3.0) / 2, c = 0.5;
    int back = 1;
    for (int k = 0; k < 4 && back < 3 && back + (4 - k) >= 3; ++k) {
        const double phi = k * kPi / 2;
        if (back_face(frame.to_world(Vec3{s * std::cos(phi), s * std::sin(phi), c}))) ++back;
    }
    return back >= 3;
}

}  // namespace omis
