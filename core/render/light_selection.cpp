// The light selector's build: bounds of lights and clusters, the binary tree
// and its collapse into wide nodes, the power CDF (the walk: light_tree_walk.cpp).
#include "render/light_selection.h"

#include <algorithm>
#include <cfloat>
#include <cstring>
#include <cmath>
#include <stdexcept>
#include <string>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "render/light_tree_detail.h"
#include "sampling/discrete.h"

namespace omis {
namespace {

// The cone that holds both cones (pbrt-v4's DirectionCone Union): axis a.axis
// rotated toward b.axis so that the new half-angle just covers both.
void merge_cones(LightSelector::Bounds& a, const LightSelector::Bounds& b) {
    const double theta_a = std::acos(std::clamp(a.cos_theta_o, -1.0, 1.0));
    const double theta_b = std::acos(std::clamp(b.cos_theta_o, -1.0, 1.0));
    const double theta_d = angle_between(a.axis, b.axis);
    if (std::min(theta_d + theta_b, kPi) <= theta_a) return;
    if (std::min(theta_d + theta_a, kPi) <= theta_b) {
        a.axis = b.axis;
        a.cos_theta_o = b.cos_theta_o;
        return;
    }
    const double theta_o = 0.5 * (theta_a + theta_d + theta_b);
    const Vec3 rotation_axis = cross(a.axis, b.axis);
    if (theta_o >= kPi || length(rotation_axis) == 0) {
        a.cos_theta_o = -1;  // every direction
        return;
    }
    // Rodrigues: rotate a.axis by theta_o − theta_a about the unit rotation axis.
    const Vec3 k = normalize(rotation_axis);
    const double r = theta_o - theta_a, c = std::cos(r), s = std::sin(r);
    a.axis = normalize(a.axis * c + cross(k, a.axis) * s + k * (dot(k, a.axis) * (1 - c)));
    a.cos_theta_o = std::cos(theta_o);
}

LightSelector::Bounds merge(LightSelector::Bounds a, const LightSelector::Bounds& b) {
    if (!(b.power > 0)) return a;
    if (!(a.power > 0)) return b;
    a.lo = component_min(a.lo, b.lo);
    a.hi = component_max(a.hi, b.hi);
    a.power += b.power;
    merge_cones(a, b);
    a.cos_theta_e = std::min(a.cos_theta_e, b.cos_theta_e);
    a.two_sided = a.two_sided || b.two_sided;
    return a;
}

LightSelector::Bounds box_of(std::initializer_list<Vec3> points) {
    LightSelector::Bounds b;
    b.lo = b.hi = *points.begin();
    for (const Vec3& p : points) {
        b.lo = component_min(b.lo, p);
        b.hi = component_max(b.hi, p);
    }
    return b;
}

}  // namespace

double rescale_within(double u, double lo, double width) {
    const double r = (u - lo) / width;
    return r > 0 ? std::min(r, std::nextafter(1.0, 0.0)) : 0.0;  // NaN (no width): 0
}

// pbrt-v4's LightBounds::Importance: power over squared distance, times the
// cosine bounds at the emitter (θ' = θw − θo − θb must stay within θe) and at
// the receiver (θi − θb below the horizon gives nothing). θb bounds the angle
// the box subtends from x, so every light in the box gets at most this.
void LightSelector::Bounds::finish() {
    centre = (lo + hi) * 0.5;
    radius2 = 0.25 * dot(hi - lo, hi - lo);
    sin_theta_o = std::sqrt(std::max(0.0, 1 - cos_theta_o * cos_theta_o));
}

namespace {

// pbrt-v4's LightBounds::Importance, with the angle differences taken by
// their sines and cosines (cos(α − β) = cos α cos β + sin α sin β): four
// square roots and one division per evaluation, as a draw among 100k lights
// makes ~34 of them.
// horizon: whether a light below the horizon of (x, n) gets 0 (a region's
// points have other normals: then it only weighs less).
double importance_of(const Vec3& centre, double radius, double power, const Vec3& axis,
                     double cos_theta_o, double sin_theta_o, double cos_theta_e,
                     bool two_sided, const Vec3& x, const Vec3& n, bool horizon = true) {
    if (!(power > 0)) return 0;
    const Vec3 d = x - centre;
    const double dist2 = dot(d, d), radius2 = radius * radius;
    if (dist2 <= radius2) return power / std::max(radius2, 1e-300);  // x among the lights

    const double inv_dist = 1 / std::sqrt(dist2);
    const Vec3 wi = d * inv_dist;  // from the lights toward x
    // θb: the half-angle the bounding sphere subtends from x.
    const double sin_b = std::min(1.0, radius * inv_dist);
    const double cos_b = std::sqrt(std::max(0.0, 1 - sin_b * sin_b));
    // θx = max(0, θw − θo): how far x lies outside the cone of normals.
    double cos_w = dot(axis, wi);
    if (two_sided) cos_w = std::abs(cos_w);
    double cos_x = 1, sin_x = 0;
    if (cos_w < cos_theta_o) {
        const double sin_w = std::sqrt(std::max(0.0, 1 - cos_w * cos_w));
        cos_x = cos_w * cos_theta_o + sin_w * sin_theta_o;
        sin_x = std::max(0.0, sin_w * cos_theta_o - cos_w * sin_theta_o);
    }
    // θ' = max(0, θx − θb) must stay within θe. A small allowance keeps
    // lights exactly at a bound's edge sampleable.
    const double cos_p = cos_x >= cos_b ? 1.0 : cos_x * cos_b + sin_x * sin_b;
    if (cos_p < cos_theta_e - 1e-9) return 0;
    // At the receiver: max(0, θi − θb) below the horizon gives nothing.
    const double cos_n = -dot(n, wi);
    double cos_i = 1;
    if (cos_n < cos_b) {
        const double sin_n = std::sqrt(std::max(0.0, 1 - cos_n * cos_n));
        cos_i = cos_n * cos_b + sin_n * sin_b;
    }
    if (horizon && cos_i < -1e-9) return 0;
    return power * std::max(cos_p, 1e-9) * std::max(cos_i, 1e-9) * (inv_dist * inv_dist);
}

}  // namespace

// A region's bound (grow > 0): the directions from a light within the
// bounding sphere toward a point within `grow` of x are those from the
// sphere grown by `grow` toward x itself, so the grown sphere seen from x
// bounds them all.
double LightSelector::Bounds::importance(const Vec3& x, const Vec3& n, double grow) const {
    return importance_of(centre, std::sqrt(radius2) + grow, power, axis, cos_theta_o,
                         sin_theta_o, cos_theta_e, two_sided, x, n, !(grow > 0));
}

LightSelector::PackedBounds::PackedBounds(const Bounds& b) {
    // The rounded centre moves by up to `shift`: the radius grows by as much.
    double shift2 = 0;
    for (int i = 0; i < 3; ++i) {
        centre[i] = float(b.centre[i]);
        shift2 += (b.centre[i] - centre[i]) * (b.centre[i] - centre[i]);
    }
    radius = round_up(std::sqrt(b.radius2) + std::sqrt(shift2));
    power = b.power > 0 ? std::max(float(b.power), 1e-30f) : 0.0f;
    for (int i = 0; i < 3; ++i) axis[i] = float(b.axis[i]);
    // The rounded axis is off by ~1e-7 rad: widen both cones by 1e-6 rad.
    const double widen = 1e-6, theta_o = std::acos(std::clamp(b.cos_theta_o, -1.0, 1.0));
    cos_theta_o = round_down(std::cos(std::min(kPi, theta_o + widen)));
    // cos rounded down, sin up: cos(θw − θo) only grows.
    sin_theta_o = round_up(std::sin(std::min(kPi, theta_o + widen)));
    const double theta_e = std::acos(std::clamp(b.cos_theta_e, -1.0, 1.0));
    cos_theta_e = round_down(std::cos(std::min(kPi, theta_e + widen)));
    two_sided = b.two_sided;
}

double LightSelector::PackedBounds::importance(const Vec3& x, const Vec3& n,
                                               double grow) const {
    return importance_of(Vec3(centre[0], centre[1], centre[2]), double(radius) + grow, power,
                         Vec3(axis[0], axis[1], axis[2]), cos_theta_o, sin_theta_o,
                         cos_theta_e, two_sided, x, n, !(grow > 0));
}

namespace {

// What a light's bounds weigh in importance(): π times the irradiance it
// gives at unit distance, facing it — so that the estimate compares lights of
// different kinds as their contributions compare. Light::power (the flux)
// does not: a point light's is 4π I against π I of irradiance, and a
// two-sided area light's counts both sides although a point sees only one
// (importance() already takes the side facing it). With the flux, the tree
// drew a two-sided emissive mesh twice as often, against a one-sided lamp, as
// its light deserves (issue 8's emissive_mesh race scene).
double weight_of(const Light& l, double scene_radius) {
    const double flux = l.power(scene_radius);
    switch (l.type) {
        case LightType::Point:
        case LightType::Spot: return flux / 4;
        case LightType::Rect:
        case LightType::Ellipse:
        case LightType::Triangle: return l.two_sided ? flux / 2 : flux;
        // A mesh light is compact (Scene::commit): seen from afar it shows
        // about a quarter of its area, as a convex body does.
        case LightType::Mesh: return flux / 8;
        default: return flux;
    }
}

}  // namespace

std::optional<LightSelector::Bounds> LightSelector::bounds_of(const Light& l,
                                                              double scene_radius) {
    Bounds b;
    switch (l.type) {
        case LightType::Rect: {
            const RectLight& r = l.rect;
            b = box_of({r.corner, r.corner + r.edge_u, r.corner + r.edge_v,
                        r.corner + r.edge_u + r.edge_v});
            b.axis = normalize(cross(r.edge_u, r.edge_v));
            break;
        }
        case LightType::Ellipse: {
            const EllipseLight& e = l.ellipse;
            b = box_of({e.center + e.axis_a + e.axis_b, e.center + e.axis_a - e.axis_b,
                        e.center - e.axis_a + e.axis_b, e.center - e.axis_a - e.axis_b});
            b.axis = normalize(cross(e.axis_a, e.axis_b));
            break;
        }
        case LightType::Triangle: {
            const TriangleLight& t = l.triangle;
            b = box_of({t.p0, t.p1, t.p2});
            b.axis = normalize(cross(t.p1 - t.p0, t.p2 - t.p0));
            break;
        }
        case LightType::Mesh: {
            // Its bounding sphere, emitting every way (as a sphere light).
            const Vec3 r(l.radius, l.radius, l.radius);
            b = box_of({l.position - r, l.position + r});
            b.cos_theta_o = -1.0;
            b.cos_theta_e = 0.0;
            b.power = weight_of(l, scene_radius);
            b.finish();
            return b;
        }
        case LightType::Point:
        case LightType::Spot: {
            const Vec3 r(l.radius, l.radius, l.radius);
            b = box_of({l.position - r, l.position + r});
            b.axis = l.type == LightType::Spot ? l.spot_axis : Vec3(0, 0, 1);
            b.cos_theta_o = l.type == LightType::Spot ? l.spot_cos_half : -1.0;
            // A sphere light is a disk facing the receiver: it leaves up to 90°
            // off the direction to x; a delta light only along it.
            b.cos_theta_e = l.radius > 0 ? 0.0 : 1.0;
            b.power = weight_of(l, scene_radius);
            b.finish();
            return b;
        }
        case LightType::Sun:
        case LightType::World: return std::nullopt;
    }
    // Planar lights: normal cone of half-angle 0, leaving up to 90° off it, or
    // up to half the spread (Blender's spread gives nothing beyond s/2).
    b.cos_theta_o = 1;
    b.cos_theta_e = l.spread < kPi ? std::cos(0.5 * l.spread) : 0.0;
    b.two_sided = l.two_sided;
    b.power = weight_of(l, scene_radius);
    b.finish();
    return b;
}

LightSelector::LightSelector(Kind kind, const std::vector<Light>& lights,
                             const std::vector<std::uint32_t>& ids, double scene_radius)
    : kind_(kind), ids_(ids), records_(lights.data()), per_light_(lights.size()) {
    for (std::uint32_t id : ids_) {
        if (id >= lights.size() || per_light_[id].role != PerLight::Absent)
            throw std::invalid_argument("ids: light " + std::to_string(id) +
                                        " is out of range or repeated");
        per_light_[id].role = PerLight::Selected;
    }
    if (kind_ == Kind::Power) {
        for (std::uint32_t id : ids_) probability_.push_back(lights[id].power(scene_radius));
        // A light whose power rounds to zero keeps a tiny share.
        normalise_weights(probability_);
        for (std::size_t i = 0; i < ids_.size(); ++i) per_light_[ids_[i]].weight = probability_[i];
        cumulate(probability_, cdf_);
    }
    if (kind_ == Kind::Tree) {
        std::vector<Entry> entries;
        entries.reserve(ids_.size());
        for (std::uint32_t id : ids_) {
            const auto b = bounds_of(lights[id], scene_radius);
            if (!b) {
                unbounded_.push_back(id);
                per_light_[id].role = PerLight::Unbounded;
            }
            else if (b->power > 0) entries.push_back({*b, id});
            // Lights of zero power add nothing and are never drawn.
        }
        if (!entries.empty()) {
            // A binary tree of L leaves has 2L − 1 nodes: reserved, so that
            // no growth copies them.
            nodes_.reserve(2 * entries.size() - 1);
            build_bounds_.reserve(2 * entries.size() - 1);
            std::vector<Keyed> keys(entries.size());
            for (std::uint32_t i = 0; i < keys.size(); ++i)
                keys[i] = {entries[i].bounds.lo + entries[i].bounds.hi, i};
            build(entries, keys, 0, entries.size(), 0);
            // build() left `keys` in leaf order.
            order_.resize(entries.size() + 1);
            clusters_ = true;
            for (std::size_t i = 0; i < entries.size(); ++i) {
                const Entry& e = entries[keys[i].entry];
                order_[i].light = e.light;
                order_[i + 1].cdf = order_[i].cdf + e.bounds.power;
                PerLight& l = per_light_[e.light];
                l.position = std::uint32_t(i);
                l.weight = order_[i + 1].cdf - order_[i].cdf;
                clusters_ = clusters_ && order_[i + 1].cdf > order_[i].cdf;
            }
            root_ = nodes_[0].bounds;
            collapse(0, 0, 0);
        }
        nodes_ = {};
        build_bounds_ = {};
    }
}

// Depth first, the first child right after its parent. Splits at the median
// centroid along the widest axis of the centroids: a balanced tree of depth
// ⌈log2 L⌉; the triangles of one mesh stay together in their own subtrees.
std::uint32_t LightSelector::build(const std::vector<Entry>& entries, std::vector<Keyed>& keys,
                                   std::size_t begin, std::size_t end, int depth) {
    if (depth >= 64) throw std::length_error("light tree: deeper than 64 levels");
    const std::uint32_t index = std::uint32_t(nodes_.size());
    nodes_.emplace_back();
    build_bounds_.emplace_back();
    nodes_[index].first = std::uint32_t(begin);
    nodes_[index].end = std::uint32_t(end);
    if (end - begin == 1) {
        const Entry& leaf = entries[keys[begin].entry];
        build_bounds_[index] = leaf.bounds;
        nodes_[index].bounds = PackedBounds(leaf.bounds);
        nodes_[index].light = leaf.light;
        return index;
    }
    Vec3 lo = keys[begin].twice_centre * 0.5, hi = lo;
    for (std::size_t i = begin; i < end; ++i) {
        const Vec3 c = keys[i].twice_centre * 0.5;
        lo = component_min(lo, c);
        hi = component_max(hi, c);
    }
    const Vec3 extent = hi - lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const std::size_t mid = begin + (end - begin) / 2;
    // The median along the axis, selected among the small keys rather than
    // the entries: nth_element's steps depend only on the comparisons, the
    // same lo + hi as the entries', so the tree is the one selecting the
    // entries would give.
    std::nth_element(keys.begin() + begin, keys.begin() + mid, keys.begin() + end,
                     [axis](const Keyed& a, const Keyed& b) {
                         return a.twice_centre[axis] < b.twice_centre[axis];
                     });
    const std::uint32_t first = build(entries, keys, begin, mid, depth + 1);
    const std::uint32_t second = build(entries, keys, mid, end, depth + 1);
    nodes_[index].second_child = second;
    Bounds& b = build_bounds_[index];
    b = merge(build_bounds_[first], build_bounds_[second]);
    b.finish();
    nodes_[index].bounds = PackedBounds(b);
    return index;
}

// The wide node of binary node `binary`: its children's children (a child
// that is a leaf stays itself). `trail` holds the choices down to here.
std::uint32_t LightSelector::collapse(std::uint32_t binary, std::uint64_t trail, int depth) {
    if (depth >= 32) throw std::length_error("light tree: deeper than 32 wide levels");
    const std::uint32_t index = std::uint32_t(wide_.size());
    wide_.emplace_back();
    links_.emplace_back();
    child_cdf_.emplace_back();
    std::uint32_t members[kWidth];
    int count = 0;
    if (nodes_[binary].light != ~0u) {
        members[count++] = binary;  // a tree of one light
    } else {
        for (std::uint32_t child : {binary + 1, nodes_[binary].second_child}) {
            if (nodes_[child].light != ~0u) {
                members[count++] = child;
            } else {
                members[count++] = child + 1;
                members[count++] = nodes_[child].second_child;
            }
        }
    }
    for (int i = 0; i < count; ++i) {
        const Node& member = nodes_[members[i]];
        const std::uint64_t path = trail | (std::uint64_t(i) << (2 * depth));
        wide_[index].set(i, member.bounds);
        WideLinks& links = links_[index];
        links.start[i] = member.first;
        links.start[i + 1] = member.end;  // the next child's start, or the end
        child_cdf_[index].cdf[i] = order_[member.first].cdf;
        child_cdf_[index].cdf[i + 1] = order_[member.end].cdf;
        if (member.light != ~0u) {
            links_[index].index[i] = member.light;
            links_[index].is_leaf |= std::uint8_t(1u << i);
            per_light_[member.light].trail = path;
        } else {
            const std::uint32_t below = collapse(members[i], path, depth + 1);
            links_[index].index[i] = below;  // links_ may have moved: index anew
        }
    }
    links_[index].count = std::uint8_t(count);
    return index;
}

void LightSelector::WideNode::set(int i, const PackedBounds& b) {
    cx[i] = b.centre[0], cy[i] = b.centre[1], cz[i] = b.centre[2];
    radius[i] = b.radius, power[i] = b.power;
    ax[i] = b.axis[0], ay[i] = b.axis[1], az[i] = b.axis[2];
    cos_theta_o[i] = b.cos_theta_o, sin_theta_o[i] = b.sin_theta_o;
    cos_theta_e[i] = b.cos_theta_e, two_sided[i] = b.two_sided ? 1.0f : 0.0f;
}

}  // namespace omis
