#include "render/light_selection.h"

#include <algorithm>
#include <cfloat>
#include <cstring>
#include <cmath>
#include <stdexcept>
#include <string>

#if defined(__SSE__)
#include <xmmintrin.h>

#include "sampling/discrete.h"
#endif

namespace omis {
namespace {

// A tree node is a cluster at a receiver — its lights drawn ∝ power, no
// longer ∝ the importance of its children — where its bounding sphere
// subtends less than asin(kClusterSine) from the receiver and its normal
// cone is narrower than acos(kClusterCone): the importance of its lights
// then differs by about ±2·kClusterSine in distance and by the spread of
// their normals, so a draw by power costs a little variance (bench/results/
// emitters.txt) and takes a binary search in place of the walk down the
// rest of the tree — the walk's length then grows with the angular size of
// the lights, not with their number.
constexpr double kClusterSine = 0.1;
constexpr double kClusterCone = 0.7;

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

// The float next to f, toward zero (down) or away from it (up), for f > 0:
// the neighbours of a positive float are its bit pattern ∓ 1 (+∞'s lower
// neighbour is FLT_MAX). std::nextafter's library call was ~7 % of an
// importance evaluation (round_up of a region's radius at every one).
float next_down_positive(float f) {
    std::uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    --bits;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}
float next_up_positive(float f) {
    std::uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    ++bits;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

float round_down(double v) {
    float f = float(v);
    if (!(double(f) > v)) return f;
    return f > 0 ? next_down_positive(f) : std::nextafter(f, -INFINITY);
}
float round_up(double v) {
    float f = float(v);
    if (!(double(f) < v)) return f;
    return f > 0 && f < INFINITY ? next_up_positive(f) : std::nextafter(f, INFINITY);
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

namespace {

// Four floats, with GCC's vector arithmetic (SSE on x86-64).
typedef float F4 __attribute__((vector_size(16)));
typedef double D4 __attribute__((vector_size(32)));  // four doubles (two SSE registers)

F4 load(const float* p) {
    F4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
F4 splat(double a) { return F4{} + float(a); }
F4 sqrt4(F4 v) {
#if defined(__SSE__)
    return _mm_sqrt_ps(v);
#else
    for (int i = 0; i < 4; ++i) v[i] = std::sqrt(v[i]);
    return v;
#endif
}
F4 max4(F4 a, F4 b) { return a > b ? a : b; }  // b where a is NaN
F4 min4(F4 a, F4 b) { return a < b ? a : b; }
// float(x − double(c[i])) in each lane: the difference in double, then rounded.
F4 offset4(double x, const float* c) {
    const D4 xs = {x, x, x, x};  // not D4{} + x, which turns x = −0 into +0
    return __builtin_convertvector(xs - __builtin_convertvector(load(c), D4), F4);
}
// Bit i set where lane i of the comparison result `mask` holds.
template <class Mask>
std::uint32_t bits_of(Mask mask) {
#if defined(__SSE__)
    F4 m;
    std::memcpy(&m, &mask, sizeof m);
    return std::uint32_t(_mm_movemask_ps(m));
#else
    std::uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) bits |= mask[i] ? 1u << i : 0u;
    return bits;
#endif
}

}  // namespace

// importance_of in four lanes, in single precision: the same bounds, with
// cull allowances of 1e-4 (float's rounding of the cosines is ~1e-7), and a
// value that reaches kept at least FLT_MIN, so that underflow never tells a
// reaching light from one that cannot reach.
std::uint32_t LightSelector::WideNode::importance(const Vec3& x, const Vec3& n, double grow,
                                                  float out[kWidth]) const {
    // A region (grow > 0): bounds grown by its radius, no horizon cull.
    const bool horizon = !(grow > 0);
    const F4 power4 = load(power), r = load(radius) + (horizon ? 0.0f : round_up(grow)),
             r2 = r * r;
    // x − centre in double, then rounded: x itself in float could be off by
    // more than a small light's radius far from the origin.
    const F4 dx = offset4(x.x, cx), dy = offset4(x.y, cy), dz = offset4(x.z, cz);
    const F4 dist2 = dx * dx + dy * dy + dz * dz;
    const F4 inv_dist = 1.0f / sqrt4(dist2);
    const F4 wx = dx * inv_dist, wy = dy * inv_dist, wz = dz * inv_dist;
    const F4 sin_b = min4(r * inv_dist, splat(1));
    const F4 cos_b = sqrt4(max4(1.0f - sin_b * sin_b, splat(0)));
    F4 cos_w = load(ax) * wx + load(ay) * wy + load(az) * wz;
    cos_w = load(two_sided) > 0.0f && cos_w < 0.0f ? -cos_w : cos_w;
    const F4 sin_w = sqrt4(max4(1.0f - cos_w * cos_w, splat(0)));
    const F4 cos_o = load(cos_theta_o), sin_o = load(sin_theta_o);
    const auto outside = cos_w < cos_o;
    const F4 cos_x = outside ? cos_w * cos_o + sin_w * sin_o : splat(1);
    const F4 sin_x = outside ? max4(sin_w * cos_o - cos_w * sin_o, splat(0)) : splat(0);
    const F4 cos_p = cos_x >= cos_b ? splat(1) : cos_x * cos_b + sin_x * sin_b;
    const F4 cos_n = -(splat(n.x) * wx + splat(n.y) * wy + splat(n.z) * wz);
    const F4 sin_n = sqrt4(max4(1.0f - cos_n * cos_n, splat(0)));
    const F4 cos_i = cos_n >= cos_b ? splat(1) : cos_n * cos_b + sin_n * sin_b;
    F4 value = power4 * max4(cos_p, splat(1e-9)) * max4(cos_i, splat(1e-9)) * inv_dist * inv_dist;
    value = max4(value, splat(FLT_MIN));
    const F4 below = horizon ? splat(-1e-4f) : splat(-INFINITY);
    value = cos_p < load(cos_theta_e) - 1e-4f || cos_i < below ? splat(0) : value;
    value = dist2 <= r2 ? power4 / max4(r2, splat(FLT_MIN)) : value;  // x among the lights
    value = power4 > 0.0f ? value : splat(0);
    std::memcpy(out, &value, sizeof value);
    const auto cluster = r2 < float(kClusterSine * kClusterSine) * dist2 &&
                         cos_o >= float(kClusterCone) && power4 > 0.0f;
    return bits_of(cluster);
}

std::uint32_t LightSelector::child_importance(std::uint32_t index, const Receiver& at,
                                              float importance[kWidth]) const {
    const WideLinks& links = links_[index];
    const std::uint32_t clusters = wide_[index].importance(at.x, at.n, at.radius, importance);
    return clusters_ ? clusters & ~std::uint32_t(links.is_leaf) & ((1u << links.count) - 1) : 0;
}

// Inline in its two callers, as child_probabilities was one function
// before remember() shared its second half (~5 % of its instructions).
__attribute__((always_inline)) inline void LightSelector::probabilities_from(
    std::uint32_t index, const float importance[kWidth], double p[kWidth]) const {
    const int count = links_[index].count;
    double total = 0;
#pragma GCC unroll 4
    for (int i = 0; i < count; ++i) total += p[i] = double(importance[i]);
    if (!(total > 0)) {
        // The parent's looser bounds reached (x, n) but no child's do: no
        // light below can add anything; split by power (all are positive).
        total = 0;
        for (int i = 0; i < count; ++i) total += p[i] = double(wide_[index].power[i]);
    }
    for (int i = 0; i < count; ++i) p[i] /= total;
}

std::uint32_t LightSelector::child_probabilities(std::uint32_t index, const Receiver& at,
                                                 double p[kWidth]) const {
    float importance[kWidth];
    const std::uint32_t clusters = child_importance(index, at, importance);
    probabilities_from(index, importance, p);
    return clusters;
}

void LightSelector::focus(Memo& memo, const Receiver& at) const {
    static_assert(Memo::kSlots == 1u << 11, "slot_of's shift");
    const Vec3 &x = at.x, &n = at.n;
    if (memo.owner != this || memo.slots.empty()) {
        memo.owner = this;
        memo.slots.assign(Memo::kSlots, Memo::Entry{});
        memo.stamp = 0;
    }
    const bool same = !memo.refocus && memo.stamp > 0 && memo.x.x == x.x && memo.x.y == x.y &&
                      memo.x.z == x.z && memo.n.x == n.x && memo.n.y == n.y &&
                      memo.n.z == n.z && memo.radius == at.radius;
    if (same) return;
    if (++memo.stamp == 0) {  // wrapped: forget everything
        std::fill(memo.slots.begin(), memo.slots.end(), Memo::Entry{});
        memo.stamp = 1;
    }
    memo.refocus = false;
    memo.x = x;
    memo.n = n;
    memo.radius = at.radius;
    memo.drawn = ~0u;
    // The kept nodes go where the memo looks for them; their probabilities
    // are made at their first use (remember), as a pass may not walk them all.
    constexpr std::uint32_t node_mask = (1u << KeptNode::kClusterShift) - 1;
    memo.kept_count = 0;
    for (; memo.kept_count < memo.kept_capacity; ++memo.kept_count) {
        const std::uint32_t node = memo.kept[memo.kept_count].node_and_clusters;
        if (node == KeptNode::kNone) break;
        Memo::Entry& e = memo.slots[slot_of(node & node_mask)];
        e.node = node & node_mask;
        e.kept_stamp = memo.stamp;
        e.kept_index = std::uint8_t(memo.kept_count);
    }
    // A node kept at this receiver was walked to: the root reached it.
    memo.root_reaches =
        memo.kept_count > 0 || (!wide_.empty() && root_.importance(x, n, at.radius) > 0);
}

// A kept node's probabilities from its importances: ~5 of a texel's walks'
// steps in a one-round later pass on the race's emissive_mesh, which through
// remember's call cost about twice the instructions.
__attribute__((always_inline)) inline void LightSelector::take_kept(std::uint32_t index,
                                                                    Memo& memo,
                                                                    Memo::Entry& e) const {
    const KeptNode& kept = memo.kept[e.kept_index];
    e.clusters = std::uint8_t(kept.node_and_clusters >> KeptNode::kClusterShift);
    probabilities_from(index, kept.importance, e.p);
    e.stamp = memo.stamp;
    e.kept_stamp = 0;  // p is made
}

// Inline in sample() and pmf(): every step of a walk comes here, and most
// find their entry.
__attribute__((always_inline)) inline const double* LightSelector::child_probabilities(
    std::uint32_t index, const Receiver& at, Memo* memo, double scratch[kWidth],
    std::uint32_t& clusters) const {
    if (!memo) {
        clusters = child_probabilities(index, at, scratch);
        return scratch;
    }
    // The memo is focused on (x, n): sample and pmf call root_reaches first.
    Memo::Entry& e = memo->slots[slot_of(index)];
    if (e.stamp != memo->stamp || e.node != index) {
        if (memo->kept_capacity > 0) {
            if (e.kept_stamp == memo->stamp && e.node == index) take_kept(index, *memo, e);
            else remember(index, at, *memo, e);
        } else {
            e.node = index;
            e.stamp = memo->stamp;
            e.clusters = std::uint8_t(child_probabilities(index, at, e.p));
        }
    }
    clusters = e.clusters;
    return e.p;
}

// Out of line: the walk's usual step finds its entry in the memo.
__attribute__((noinline)) void LightSelector::remember(std::uint32_t index, const Receiver& at,
                                                       Memo& memo, Memo::Entry& e) const {
    static_assert(sizeof(KeptNode::importance) == sizeof(float) * kWidth, "a node's children");
    constexpr std::uint32_t node_mask = (1u << KeptNode::kClusterShift) - 1;
    // (A kept node that focus placed at its slot is take_kept's.)
    const KeptNode* found = nullptr;
    if (e.kept_stamp == memo.stamp || e.stamp == memo.stamp) {
        // Another node of this focus took the slot: a kept node may have
        // lost it. (Otherwise focus would have placed a kept `index` here.)
        for (std::size_t j = 0; j < memo.kept_count && !found; ++j)
            if ((memo.kept[j].node_and_clusters & node_mask) == index) found = &memo.kept[j];
    }
    float importance[kWidth];
    if (found) {
        std::memcpy(importance, found->importance, sizeof importance);
        e.clusters = std::uint8_t(found->node_and_clusters >> KeptNode::kClusterShift);
    } else {
        e.clusters = std::uint8_t(child_importance(index, at, importance));
        if (memo.kept_count < memo.kept_capacity && index <= node_mask) {
            KeptNode& k = memo.kept[memo.kept_count++];
            k.node_and_clusters = index | std::uint32_t(e.clusters) << KeptNode::kClusterShift;
            std::memcpy(k.importance, importance, sizeof importance);
        }
    }
    probabilities_from(index, importance, e.p);
    e.node = index;
    e.stamp = memo.stamp;
    e.kept_stamp = 0;  // p is made
}

// Inline in sample() and pmf(), as each of their calls starts here.
__attribute__((always_inline)) inline bool LightSelector::root_reaches(const Receiver& at,
                                                                    Memo* memo) const {
    if (wide_.empty()) return false;
    if (!memo) return root_.importance(at.x, at.n, at.radius) > 0;
    focus(*memo, at);
    return memo->root_reaches;
}

bool LightSelector::may_reach(const Vec3& x, const Vec3& n) const {
    if (kind_ != Kind::Tree) return !ids_.empty();
    return !unbounded_.empty() || root_reaches(Receiver{x, n, 0.0}, nullptr);
}

// position_in's first guess in child i's range: where u would fall among
// lights of equal power.
std::uint32_t LightSelector::guess_in(const WideLinks& links, int i, double u) {
    const std::uint32_t begin = links.start[i], end = links.start[i + 1];
    return std::min(begin + std::uint32_t(u * double(end - begin)), end - 1);
}

// The lights of a cluster are alike (kClusterSine), so their powers are too,
// mostly: the position a uniform u would take among them is a good first
// guess, and the search gallops out from it. Among 100k lights a binary
// search over the whole range waited on a cache miss at nearly every step;
// this one reads the guess's line and seldom another. The guess is the
// answer for about half the draws (bench_emitters' sphere of 99k triangles,
// texels): its light's record, which the caller reads next, is started on
// too. (A secant step from the guess on its own power read fewer lines, but
// its second read waits on the first, where the gallop's first probes are
// issued at once: position_in took 1.3x the time.)
std::uint32_t LightSelector::position_in(const WideLinks& links, const ChildCdf& range, int i,
                                        double u) const {
    const std::uint32_t begin = links.start[i], end = links.start[i + 1];
    const double target = range.cdf_point(i, u);
    // The last position p in [begin, end) with order_[p].cdf <= target (begin
    // at least): the interval that holds target, as upper_bound over the range
    // finds it. `below` holds where that is true.
    auto below = [&](std::uint32_t p) { return p == begin || order_[p].cdf <= target; };
    const std::uint32_t guess = guess_in(links, i, u);
    prefetch_record(records_ + order_[guess].light);
    // Bracket the answer in [lo, hi] by steps of 1, 2, 4, … away from the guess.
    std::uint32_t lo = begin, hi = end - 1;
    if (below(guess)) {
        lo = guess;
        for (std::uint32_t step = 1; lo < hi; step *= 2) {
            const std::uint32_t probe = lo + std::min(step, hi - lo);
            if (!below(probe)) {
                hi = probe - 1;
                break;
            }
            lo = probe;
        }
    } else {
        hi = guess - 1;
        for (std::uint32_t step = 1; lo < hi; step *= 2) {
            const std::uint32_t probe = hi - std::min(step, hi - lo);
            if (below(probe)) {
                lo = probe;
                break;
            }
            hi = probe - 1;
        }
    }
    while (lo < hi) {
        const std::uint32_t mid = lo + (hi - lo + 1) / 2;
        if (below(mid)) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

std::optional<SelectedLight> LightSelector::sample(const Receiver& at, double u,
                                                   Memo* memo) const {
    const PartialDraw draw = begin_draw(at, u, memo);
    const std::optional<SelectedLight> light = finish_draw(draw);
    if (memo && draw.from_tree && light) memo->drawn = light->light, memo->drawn_pmf = light->pmf;
    return light;
}

LightSelector::PartialDraw LightSelector::begin_draw(const Receiver& at, double u,
                                                     Memo* memo) const {
    PartialDraw draw;
    if (ids_.empty()) return draw;
    u = std::clamp(u, 0.0, std::nextafter(1.0, 0.0));
    if (kind_ == Kind::Uniform) {
        const double n = double(ids_.size());
        const std::size_t i = std::min(std::size_t(u * n), ids_.size() - 1);
        draw.light = SelectedLight{ids_[i], 1.0 / n, rescale_within(u * n, double(i), 1.0)};
        return draw;
    }
    if (kind_ == Kind::Power) {
        const std::size_t i = std::min<std::size_t>(
            std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin(), ids_.size() - 1);
        const double lo = i > 0 ? cdf_[i - 1] : 0.0;
        draw.light = SelectedLight{ids_[i], probability_[i], rescale_within(u, lo, cdf_[i] - lo)};
        return draw;
    }
    // Tree: an unbounded light or the tree (where it reaches), uniformly;
    // then down the tree.
    const bool tree = root_reaches(at, memo);
    const std::size_t choices = unbounded_.size() + (tree ? 1 : 0);
    if (choices == 0) return draw;
    const std::size_t pick = std::min(std::size_t(u * double(choices)), choices - 1);
    u = rescale_within(u * double(choices), double(pick), 1.0);
    if (pick < unbounded_.size()) {
        draw.light = SelectedLight{unbounded_[pick], 1.0 / double(choices), u};
        return draw;
    }
    double pmf = 1.0 / double(choices);
    std::uint32_t node = 0;
    double scratch[kWidth];
    for (;;) {
        std::uint32_t clusters;
        const double* p = child_probabilities(node, at, memo, scratch, clusters);
        const WideLinks& links = links_[node];
        // The child whose share of [0, 1) holds u; rounding past the last
        // share falls to the last child that has one.
        int i = 0;
        double below = 0;
        while (i + 1 < links.count && !(u < below + p[i] && p[i] > 0)) below += p[i++];
        while (!(p[i] > 0) && i > 0) below -= p[--i];
        u = rescale_within(u, below, p[i]);
        pmf *= p[i];
        if (links.is_leaf & (1u << i)) {
            draw.from_tree = true;
            if (pmf > 0) draw.light = SelectedLight{links.index[i], pmf, u};  // else underflow
            return draw;
        }
        if (clusters & (1u << i)) {
            // A cluster: its lights ∝ power, u in its share of their CDF
            // (finish_draw). Its first reads start here: the guess's entry
            // (and the one after, its step's end) and the node's CDF line.
            const std::uint32_t guess = guess_in(links, i, u);
            __builtin_prefetch(&order_[guess]);
            __builtin_prefetch(&order_[guess + 1]);
            __builtin_prefetch(&child_cdf_[node]);
            draw.in_cluster = draw.from_tree = true;
            draw.node = node;
            draw.child = i;
            draw.u = u;
            draw.pmf = pmf;
            return draw;
        }
        node = links.index[i];
    }
}

std::optional<SelectedLight> LightSelector::finish_draw(const PartialDraw& draw) const {
    if (!draw.in_cluster) return draw.light;
    const WideLinks& links = links_[draw.node];
    const ChildCdf& range = child_cdf_[draw.node];
    const int i = draw.child;
    const std::uint32_t position = position_in(links, range, i, draw.u);
    const double step = order_[position + 1].cdf - order_[position].cdf;
    const double pmf = draw.pmf * (step / range.power(i));
    if (!(pmf > 0)) return std::nullopt;  // underflow below ~1e-308 only
    return SelectedLight{order_[position].light, pmf,
                         rescale_within(range.cdf_point(i, draw.u), order_[position].cdf, step)};
}

double LightSelector::pmf(const Receiver& at, std::uint32_t light, Memo* memo) const {
    if (light >= per_light_.size()) return 0;
    if (kind_ != Kind::Tree) {
        const PerLight& l = per_light_[light];
        if (l.role == PerLight::Absent) return 0;
        return kind_ == Kind::Uniform ? 1.0 / double(ids_.size()) : l.weight;
    }
    const bool tree = root_reaches(at, memo);
    // The light just drawn at `at`: the product its walk formed, without
    // reading its record (among 100k lights a cache miss).
    if (tree && memo && memo->drawn == light) return memo->drawn_pmf;
    const PerLight& l = per_light_[light];
    if (l.role == PerLight::Absent) return 0;
    const std::size_t choices = unbounded_.size() + (tree ? 1 : 0);
    if (l.role == PerLight::Unbounded) return 1.0 / double(choices);
    if (!tree) return 0;
    double pmf = 1.0 / double(choices);
    std::uint32_t node = 0;
    double scratch[kWidth];
    for (int level = 0; pmf > 0; ++level) {
        const int i = int((l.trail >> (2 * level)) & 3);
        const WideLinks& links = links_[node];
        if (i >= links.count) return 0;  // a light of zero power: not in the tree
        std::uint32_t clusters;
        pmf *= child_probabilities(node, at, memo, scratch, clusters)[i];
        if (links.is_leaf & (1u << i)) return links.index[i] == light ? pmf : 0.0;
        if (clusters & (1u << i)) {
            if (l.position < links.start[i] || l.position >= links.start[i + 1])
                return 0;  // not in the tree
            return pmf * (l.weight / child_cdf_[node].power(i));
        }
        node = links.index[i];
    }
    return 0;
}

}  // namespace omis
