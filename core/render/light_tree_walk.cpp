// The light selector's walk: a node's children's importance at a receiver
// (four lanes at once), the region memo, draws (begun and finished apart) and
// pmfs. Its build: light_selection.cpp.
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

namespace omis {
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
