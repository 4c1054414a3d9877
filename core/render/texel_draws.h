// What a bake keeps per texel from pass to pass (both calloc'd, within a
// byte budget; shared by the threads of a job: a point is shaded by one
// thread at a time, as with TexelTables).
//
// Where each texel's table draws stand (TexelDrawCounts). A light technique
// that draws from a per-texel table takes each light's shape point from that
// light's own sequence, at the light's count of draws so far
// (technique_draws.h, LightSequences). A later pass needs those counts:
// re-counting them from the earlier rounds' selections grew with the rounds
// done, ~20 % of what every later pass repeated (bench/results/budgets.txt).
// Kept here, a pass continues from them instead.
// Per point: `cells` counts (4 bytes each: per table technique, stream and
// table slot; LightingContext::keep_draw_counts). The counts of a point
// always describe a prefix of its draws — their sum is its length — so a
// call that starts elsewhere (a probe pass replaced by one from round 0) can
// tell and count again.
//
// Which probes of a texel's footprint each light reaches, for the tables
// that weigh lights by no irradiance (`uniform`, `power`: TexelReach, a byte
// per table technique and integrated light; LightingContext::keep_table_reach):
// a later pass makes the same table from them without probing again.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>

namespace omis {

template <class Cell>
class PerTexelCells {
public:
    // Most bytes kept: past them nothing is kept and every pass counts again.
    static constexpr std::size_t kByteBudget = std::size_t(32) << 20;

    // Points 0 … count − 1, `cells` cells each, all 0 (pages the first pass
    // never writes are never touched: calloc).
    void index_points(std::size_t count, std::size_t cells) {
        data_.reset();
        count_ = cells_ = 0;
        if (count == 0 || cells == 0 || count > kByteBudget / sizeof(Cell) / cells)
            return;
        data_.reset(static_cast<Cell*>(std::calloc(count * cells, sizeof(Cell))));
        if (!data_) return;
        count_ = count;
        cells_ = cells;
    }
    // Point `point`'s cells (cells() of them), or null when none are kept.
    Cell* of(std::uint64_t point) const {
        return point < count_ ? data_.get() + point * cells_ : nullptr;
    }
    std::size_t cells() const { return cells_; }
    std::size_t bytes() const { return count_ * cells_ * sizeof(Cell); }

private:
    struct Free {
        void operator()(Cell* p) const { std::free(p); }
    };
    std::unique_ptr<Cell[], Free> data_;
    std::size_t count_ = 0, cells_ = 0;
};

using TexelDrawCounts = PerTexelCells<std::uint32_t>;
using TexelReach = PerTexelCells<std::uint8_t>;

}  // namespace omis
