// Where each texel's table draws stand, kept from pass to pass of a bake.
//
// A light technique that draws from a per-texel table takes each light's
// shape point from that light's own sequence, at the light's count of draws
// so far (direct_lighting.cpp, LightStreams). A later pass needs those counts:
// re-counting them from the earlier rounds' selections grew with the rounds
// done, ~20 % of what every later pass repeated (bench/results/budgets.txt).
// Kept here, a pass continues from them instead.
//
// Per point: `cells` counts (4 bytes each: per table technique, stream and
// table slot; LightingContext::keep_draw_counts). The counts of a point
// always describe a prefix of its draws — their sum is its length — so a
// call that starts elsewhere (a probe pass replaced by one from round 0) can
// tell and count again. Shared by the threads of a job: a point is shaded by
// one thread at a time, as with TexelTables.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>

namespace omis {

class TexelDrawCounts {
public:
    // Most bytes kept: past them nothing is kept and every pass counts again.
    static constexpr std::size_t kByteBudget = std::size_t(32) << 20;

    // Points 0 … count − 1, `cells` counts each, all 0 (pages the first pass
    // never writes are never touched: calloc).
    void index_points(std::size_t count, std::size_t cells) {
        counts_.reset();
        count_ = cells_ = 0;
        if (count == 0 || cells == 0 || count > kByteBudget / sizeof(std::uint32_t) / cells)
            return;
        counts_.reset(static_cast<std::uint32_t*>(std::calloc(count * cells, sizeof(std::uint32_t))));
        if (!counts_) return;
        count_ = count;
        cells_ = cells;
    }
    // Point `point`'s counts (cells() of them), or null when none are kept.
    std::uint32_t* of(std::uint64_t point) const {
        return point < count_ ? counts_.get() + point * cells_ : nullptr;
    }
    std::size_t cells() const { return cells_; }
    std::size_t bytes() const { return count_ * cells_ * sizeof(std::uint32_t); }

private:
    struct Free {
        void operator()(std::uint32_t* p) const { std::free(p); }
    };
    std::unique_ptr<std::uint32_t[], Free> counts_;
    std::size_t count_ = 0, cells_ = 0;
};

}  // namespace omis
