// Light selection (SPEC §3 `<selection>/…`): which light a light technique
// draws toward, and the probability of drawing a given light, at a shading
// point (x, n). Both cost O(1) or O(log L) whatever the light count L, and
// need no per-point setup, so they may be evaluated at a new x for every
// sample (pbrt-v4's ShapeSampler interface).
//
// - Uniform: 1/L.
// - Power:   ∝ emitted power, by binary search in a CDF (O(log L)).
// - Tree:    a light hierarchy (Estevez & Kulla 2018, "Importance sampling of
//            many lights with adaptive tree splitting"; pbrt-v4's
//            BVHLightSampler; Cycles 3.5's light tree): a BVH over the bounded
//            lights whose nodes bound position, power and the cone of emission
//            normals; each step down picks a child ∝ a conservative estimate of
//            its contribution at (x, n). Built binary (median splits), stored
//            4-wide (two binary levels per node). A node small as seen from
//            x (a cluster: kClusterSine) is not walked further: its lights
//            are drawn ∝ power, by binary search in a CDF over the tree's
//            leaf order, where each node's lights lie side by side. Every
//            draw ends at a light: the pmfs sum to 1 wherever the tree can
//            reach (x, n).
//            Unbounded lights (sun, world) are picked uniformly beside the
//            tree.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "lights/light.h"

namespace omis {

struct SelectedLight {
    std::uint32_t light = 0;  // index into the light list the selector was built on
    double pmf = 0;
    // The selection's uniform u rescaled within the chosen light's share of
    // [0, 1): given the choice, uniform on [0, 1) and independent of it, so
    // the light's shape draw may take it as a coordinate (the points that
    // choose one light then keep the stratification of u's sequence).
    double rest = 0;
};

// (u − lo) / width in [0, 1): u's place within a share [lo, lo + width).
double rescale_within(double u, double lo, double width);

class LightSelector {
public:
    enum class Kind { Uniform, Power, Tree };

    LightSelector() = default;
    // Selects among lights[ids[i]]; `ids` must not repeat. scene_radius sizes
    // distant lights' power (Light::power).
    LightSelector(Kind kind, const std::vector<Light>& lights,
                  const std::vector<std::uint32_t>& ids, double scene_radius);

    Kind kind() const { return kind_; }
    std::size_t size() const { return ids_.size(); }
    bool empty() const { return ids_.empty(); }

    // False only where no light can reach (x, n) (tree: by its bounds; the
    // others do not know and say true).
    bool may_reach(const Vec3& x, const Vec3& n) const;

    // Where lights are drawn: a point (x, n), or with radius > 0 a region —
    // every point within `radius` of x, whatever its normal (a texel's
    // footprint; n then only weighs). A region's pmfs belong to no single
    // point: the tree's bounds are grown by the radius and not culled by
    // the horizon, so they are positive for every light that may reach any
    // point inside. A technique may therefore draw with them at any point
    // inside the region and stay unbiased (its density there is what pmf()
    // of the region gives), and a memo keeps them for all of its samples.
    struct Receiver {
        Vec3 x, n;
        double radius = 0;
    };
    // One wide node's branching at a receiver, kept beyond a memo's focus
    // (Memo::keep_in): the children's importances as the node's bounds gave
    // them — its probabilities follow from them exactly — and which children
    // are clusters. 20 bytes.
    struct KeptNode {
        static constexpr std::uint32_t kNone = ~0u;
        static constexpr int kClusterShift = 28;  // nodes past 2^28 are not kept
        std::uint32_t node_and_clusters = kNone;  // node | clusters << kClusterShift
        float importance[4] = {};
    };
    // Scratch memory of one thread that remembers the tree's branching
    // probabilities at one (x, n): the draw and the pmfs evaluated at the
    // same point then share the work near the root. A small direct-mapped
    // table (it stays in L1/L2 cache; a per-node array of 100k lights would
    // cost a cache miss per level): a node that collides is recomputed.
    class Memo {
        friend class LightSelector;

    public:
        // Where the branching computed at the receiver the memo is next
        // focused on is kept, and found again by a later focus on the same
        // receiver (a texel's next pass): up to `capacity` nodes (at most
        // 255), the first walked — the root and those below it first — in
        // slots that start out empty (KeptNode::kNone). A node found there is
        // not evaluated again: the draws and pmfs are those the bounds give.
        // The caller names the same receiver's store every time, or null.
        void keep_in(KeptNode* nodes, std::size_t capacity) {
            // Another store: focus anew, even on an equal receiver, so that
            // kept_count counts this store's nodes.
            refocus = refocus || nodes != kept;
            kept = nodes;
            kept_capacity = nodes ? std::min<std::size_t>(capacity, 255) : 0;
        }

    private:
        static constexpr std::size_t kSlots = 2048;  // a power of 2
        const LightSelector* owner = nullptr;  // one memo per selector
        Vec3 x, n;
        double radius = 0;
        std::uint32_t stamp = 0;
        bool root_reaches = false;  // at (x, n)
        bool refocus = false;
        // The last light drawn from the tree at (x, n), whose pmf the
        // technique pdfs ask for next.
        std::uint32_t drawn = ~0u;
        double drawn_pmf = 0;
        struct Entry {
            std::uint32_t node = 0, stamp = 0;  // valid when stamp is the memo's
            double p[4] = {};                   // child probabilities
            // Where focus found `node` among the kept nodes (kept[kept_index]),
            // when kept_stamp is the memo's: p is then made at its first use.
            std::uint32_t kept_stamp = 0;
            std::uint8_t kept_index = 0;
            std::uint8_t clusters = 0;  // bit i: child i is a cluster
        };
        std::vector<Entry> slots;
        KeptNode* kept = nullptr;
        std::size_t kept_capacity = 0, kept_count = 0;  // kept[0, kept_count) hold nodes
    };
    // A light drawn with u ∈ [0, 1); empty when no light can reach (x, n)
    // (tree only: every bound says so).
    std::optional<SelectedLight> sample(const Vec3& x, const Vec3& n, double u,
                                        Memo* memo = nullptr) const {
        return sample(Receiver{x, n, 0.0}, u, memo);
    }
    std::optional<SelectedLight> sample(const Receiver& at, double u, Memo* memo = nullptr) const;
    // sample() in two halves, for a caller that draws ahead of its samples:
    // begin_draw walks the tree down to where the draw ends at a light or
    // enters a cluster, and there starts reading the cluster's line of the
    // leaf-order CDF (among 100k lights a cache miss, which the walk's other
    // reads wait on); finish_draw, called later, searches that CDF. Their
    // result is sample()'s bit for bit, whatever is drawn or asked between
    // the two. Unlike sample(), they leave the memo's `drawn` as it was: the
    // caller keeps the pmf of a light it drew ahead.
    struct PartialDraw {
        std::optional<SelectedLight> light;  // the draw, unless in_cluster
        bool in_cluster = false;
        int child = 0;            // in_cluster: child `child` of wide node `node`,
        std::uint32_t node = 0;
        double u = 0, pmf = 0;    // with u rescaled within its share, the walk's pmf
        bool from_tree = false;   // the walk reached a light (sample() tells the memo)
    };
    PartialDraw begin_draw(const Receiver& at, double u, Memo* memo = nullptr) const;
    std::optional<SelectedLight> finish_draw(const PartialDraw& draw) const;
    // The probability that sample() at (x, n) returns `light` (0 for a light
    // not in the selection).
    double pmf(const Vec3& x, const Vec3& n, std::uint32_t light, Memo* memo = nullptr) const {
        return pmf(Receiver{x, n, 0.0}, light, memo);
    }
    double pmf(const Receiver& at, std::uint32_t light, Memo* memo = nullptr) const;
    // A hint that pmf(…, light) follows soon: starts reading what it needs
    // (among 100k lights, a cache miss) while the caller works on.
    void prefetch(std::uint32_t light) const {
        if (light < per_light_.size()) __builtin_prefetch(&per_light_[light]);
    }

    // What the tree bounds: an axis-aligned box, the power inside, and the
    // cone of emission directions (axis, half-angle θo, plus θe, how far past
    // a normal light still leaves). Public for tests.
    struct Bounds {
        Vec3 lo, hi;
        double power = 0;
        Vec3 axis{0, 0, 1};
        double cos_theta_o = 1, cos_theta_e = 1;
        bool two_sided = false;
        // Derived by finish(), for importance(): the box's centre and squared
        // half-diagonal, and sin θo.
        Vec3 centre;
        double radius2 = 0, sin_theta_o = 0;
        void finish();

        // Upper estimate of the light's contribution at (x, n); 0 only where
        // no light inside can reach (x, n). With grow > 0, of a region
        // (Receiver): 0 only where no light inside reaches any of it.
        double importance(const Vec3& x, const Vec3& n, double grow = 0) const;
    };
    // The bounds of one light; empty for unbounded lights (sun, world).
    static std::optional<Bounds> bounds_of(const Light& light, double scene_radius);

private:
    // Bounds in single precision, rounded so that they only grow (a wider
    // box and cones): 48 bytes, as a draw among 100k lights waits for memory.
    struct PackedBounds {
        float centre[3] = {}, radius = 0, power = 0, axis[3] = {}, cos_theta_o = 1,
              sin_theta_o = 0, cos_theta_e = 1;
        bool two_sided = false;
        PackedBounds() = default;
        explicit PackedBounds(const Bounds& b);
        double importance(const Vec3& x, const Vec3& n, double grow) const;
    };
    // The binary tree as built (then collapsed into wide nodes).
    struct Node {
        PackedBounds bounds;
        std::uint32_t second_child = 0;  // interior: first child is the next node
        std::uint32_t light = ~0u;       // leaf: light id; interior: ~0u
        std::uint32_t first = 0, end = 0;  // its lights' positions in leaf order
    };
    struct Entry {
        Bounds bounds;
        std::uint32_t light;
    };
    // An entry's box centre, doubled (lo + hi: the sort key along each
    // axis), beside its index: the build reorders these 32-byte records in
    // place of the 150-byte entries.
    struct Keyed {
        Vec3 twice_centre;
        std::uint32_t entry;
    };
    // Builds the subtree of keys[begin, end) and leaves them in leaf order.
    std::uint32_t build(const std::vector<Entry>& entries, std::vector<Keyed>& keys,
                        std::size_t begin, std::size_t end, int depth);
    // Up to four children (two levels of the binary tree) side by side: a
    // step down reads one contiguous block and evaluates four independent
    // importances, and a draw among 100k lights takes 9 steps instead of 17.
    static constexpr int kWidth = 4;
    struct alignas(64) WideNode {
        // The children's PackedBounds field by field, one lane each, so that
        // importance() evaluates the four at once: three cache lines.
        float cx[kWidth] = {}, cy[kWidth] = {}, cz[kWidth] = {}, radius[kWidth] = {},
              power[kWidth] = {}, ax[kWidth] = {}, ay[kWidth] = {}, az[kWidth] = {},
              cos_theta_o[kWidth] = {}, sin_theta_o[kWidth] = {}, cos_theta_e[kWidth] = {},
              two_sided[kWidth] = {};  // 1 or 0
        void set(int i, const PackedBounds& b);
        // PackedBounds::importance of each child in single precision (0 past
        // count, and never 0 where a child's bounds reach (x, n)). Returns
        // the children that are clusters at (x, grow): bit i for child i.
        std::uint32_t importance(const Vec3& x, const Vec3& n, double grow,
                                 float out[kWidth]) const;
    };
    // Where a wide node's children lead, apart from their bounds: a step down
    // whose probabilities a memo holds reads only these 40 bytes instead of
    // the bounds' three lines. start[i]: where child i's lights lie in leaf
    // order, [start[i], start[i + 1]) — at hand with the step, so a draw
    // inside a cluster child reads its guess's line at once.
    struct WideLinks {
        std::uint32_t index[kWidth] = {};     // wide node, or light id where is_leaf
        std::uint32_t start[kWidth + 1] = {};
        std::uint8_t count = 0, is_leaf = 0;  // is_leaf: bit i for child i
    };
    // The power CDF where a wide node's children's lights start in leaf
    // order (cdf[i] at start[i], cdf[count] at the end): what a draw inside a
    // cluster child and its pmf need of the CDF besides their own place, in
    // one cache line, read beside the guess's — where reading the CDF at both
    // ends of the range was two misses among 100k lights.
    struct alignas(64) ChildCdf {
        double cdf[kWidth + 1] = {};
        // Child i's total power, as the CDF gives it.
        double power(int i) const { return cdf[i + 1] - cdf[i]; }
        // Where u ∈ [0, 1) falls on the power CDF of child i's range.
        double cdf_point(int i, double u) const { return cdf[i] + u * power(i); }
    };
    std::uint32_t collapse(std::uint32_t binary, std::uint64_t trail, int depth);
    // The probability of each child of a wide node: ∝ the children's
    // importance, or ∝ their power where none's bounds reach (x, n) although
    // the parent's did, so that every draw ends at a light and the pmfs sum
    // to 1. Returns the children that are clusters (bit i for child i):
    // interior nodes whose bounding sphere subtends less than kClusterSine
    // from `at` (grown by its radius) and whose normals lie within
    // kClusterCone of their axis — lights alike as seen from `at`, whose
    // importance differs little from their power.
    std::uint32_t child_probabilities(std::uint32_t node, const Receiver& at,
                                      double p[kWidth]) const;
    // Its two halves: the children's importance at `at` (returns the
    // clusters), and the probabilities from that importance.
    std::uint32_t child_importance(std::uint32_t node, const Receiver& at,
                                   float importance[kWidth]) const;
    void probabilities_from(std::uint32_t node, const float importance[kWidth],
                            double p[kWidth]) const;
    // Fills the memo's entry for `node` at `at`: from the kept nodes where
    // they hold it, else evaluated (and kept where a slot is free).
    void remember(std::uint32_t node, const Receiver& at, Memo& memo, Memo::Entry& e) const;
    // remember's usual case in a later pass, inline: focus placed the kept
    // node at its slot.
    void take_kept(std::uint32_t node, Memo& memo, Memo::Entry& e) const;
    // The same through a memo focused on `at` (root_reaches does so).
    const double* child_probabilities(std::uint32_t node, const Receiver& at, Memo* memo,
                                      double scratch[kWidth], std::uint32_t& clusters) const;
    // The leaf position in child i's range whose share of the power CDF
    // holds u ∈ [0, 1) (a draw inside a cluster).
    std::uint32_t position_in(const WideLinks& links, const ChildCdf& range, int i,
                              double u) const;
    // Its first guess, which begin_draw starts reading.
    static std::uint32_t guess_in(const WideLinks& links, int i, double u);
    // Whether the root's bounds reach `at`: the tree then takes its share.
    // Focuses the memo on it.
    bool root_reaches(const Receiver& at, Memo* memo) const;
    // Sets the memo to `at`, forgetting other receivers.
    void focus(Memo& memo, const Receiver& at) const;
    // A node's slot in a memo: Fibonacci hashing spreads the depth-first
    // indices of one path.
    static std::size_t slot_of(std::uint32_t node) { return (node * 2654435769u) >> (32 - 11); }

    Kind kind_ = Kind::Uniform;
    std::vector<std::uint32_t> ids_;
    // The records of the lights the selector was built on (the scene's,
    // which outlive it): a cluster's draw starts reading its likely light's
    // record while it searches (position_in). Prefetched, never read.
    const Light* records_ = nullptr;
    // Per light id, all that pmf() reads about a light, side by side (one
    // cache miss among 100k lights).
    struct PerLight {
        enum Role : std::uint8_t { Absent, Selected, Unbounded };
        std::uint64_t trail = 0;  // Tree: child choices, root first, 2 bits each
        // Power: the pmf. Tree: the light's step of the leaf-order power CDF,
        // which its share in a cluster divides (read here, not in the CDF).
        double weight = 0;
        std::uint32_t position = 0;  // Tree: where it lies in leaf order
        Role role = Absent;       // Unbounded: sun, world beside the tree
    };
    std::vector<PerLight> per_light_;
    std::vector<double> cdf_;         // Power: cumulative over ids_
    std::vector<double> probability_; // Power: per index in ids_
    // Tree
    std::vector<Node> nodes_;           // binary, while building
    std::vector<Bounds> build_bounds_;  // per binary node, while building
    std::vector<WideNode> wide_;        // the root first
    std::vector<WideLinks> links_;      // per wide node
    std::vector<ChildCdf> child_cdf_;   // per wide node
    PackedBounds root_;
    std::vector<std::uint32_t> unbounded_;  // sun, world: uniform beside the tree
    // The bounded lights in leaf order (a node's lie side by side), each
    // beside the cumulative sum of the powers before it (order_[0].cdf = 0;
    // one more entry holds the total), for draws inside a cluster: a guess's
    // light comes with its place in the CDF. clusters_ is false where some
    // light's share of the sum rounds to 0 (a power below ~1e-16 of the
    // total): then no node is a cluster, as such a light could never be
    // drawn from one.
    struct Ordered {
        double cdf = 0;
        std::uint32_t light = ~0u;
    };
    std::vector<Ordered> order_;
    bool clusters_ = false;
};

}  // namespace omis
