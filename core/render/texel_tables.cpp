#include "render/texel_tables.h"

namespace omis {

namespace {
constexpr std::size_t kMapNode = 48;  // a map node's own bytes beside the entry
}

void TexelTables::index_points(std::size_t count) {
    if (count * sizeof(Slot) > budget_ / 4) return;  // the map then
    indexed_.reset(new Slot[count]);
    indexed_count_ = count;
    bytes_.fetch_add(count * sizeof(Slot), std::memory_order_relaxed);
}

const TexelTables::Entry* TexelTables::find(std::uint64_t texel) const {
    if (texel < indexed_count_) {
        const Slot& slot = indexed_[texel];
        return slot.kept.load(std::memory_order_acquire) ? &slot.entry : nullptr;
    }
    const auto it = entries_.find(texel);
    return it == entries_.end() ? nullptr : &it->second;
}

// Reserves the bytes first, so that threads racing near the cap never
// exceed it together.
bool TexelTables::reserve(std::size_t size) {
    std::size_t used = bytes_.load(std::memory_order_relaxed);
    do {
        if (used + size > budget_) return false;
    } while (!bytes_.compare_exchange_weak(used, used + size, std::memory_order_relaxed));
    return true;
}

void TexelTables::keep(std::uint64_t texel, Entry&& entry) {
    if (texel < indexed_count_) {
        // One thread shades a texel at a time: no other keeps this slot now.
        Slot& slot = indexed_[texel];
        if (slot.kept.load(std::memory_order_acquire)) return;
        const std::size_t size = bytes_of(entry) - sizeof(Entry) - kMapNode;  // the slot's counted
        if (!reserve(size)) return;
        slot.entry = std::move(entry);
        slot.kept.store(true, std::memory_order_release);
        indexed_kept_.fetch_add(1, std::memory_order_relaxed);
        return;
    }
    const std::size_t size = bytes_of(entry);
    if (!reserve(size)) return;
    if (!entries_.emplace(texel, std::move(entry)).second)
        bytes_.fetch_sub(size, std::memory_order_relaxed);  // kept already
}

// What an entry costs: its own size, the map's node and the heap blocks of
// its tables (with an allocator's typical 16-byte header each).
std::size_t TexelTables::bytes_of(const Entry& entry) {
    constexpr std::size_t kBlockHeader = 16;
    std::size_t total = sizeof(Entry) + kMapNode;
    if (!entry.tables.empty()) total += kBlockHeader + entry.tables.capacity() * sizeof(Table);
    for (const Table& t : entry.tables)
        total += 2 * kBlockHeader + t.lights.capacity() * sizeof(std::uint32_t) +
                 t.probability.capacity() * sizeof(double);
    return total;
}

}  // namespace omis
