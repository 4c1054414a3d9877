#include "render/texel_tables.h"

namespace omis {

const TexelTables::Entry* TexelTables::find(std::uint64_t texel) const {
    const auto it = entries_.find(texel);
    return it == entries_.end() ? nullptr : &it->second;
}

void TexelTables::keep(std::uint64_t texel, Entry&& entry) {
    const std::size_t size = bytes_of(entry);
    // Reserve the bytes first, so that threads racing near the cap never
    // exceed it together.
    std::size_t used = bytes_.load(std::memory_order_relaxed);
    do {
        if (used + size > budget_) return;
    } while (!bytes_.compare_exchange_weak(used, used + size, std::memory_order_relaxed));
    if (!entries_.emplace(texel, std::move(entry)).second)
        bytes_.fetch_sub(size, std::memory_order_relaxed);  // kept already
}

// What an entry costs: its own size, the map's node and the heap blocks of
// its tables (with an allocator's typical 16-byte header each).
std::size_t TexelTables::bytes_of(const Entry& entry) {
    constexpr std::size_t kNode = 48, kBlockHeader = 16;
    std::size_t total = sizeof(Entry) + kNode;
    if (!entry.tables.empty()) total += kBlockHeader + entry.tables.capacity() * sizeof(Table);
    for (const Table& t : entry.tables)
        total += 2 * kBlockHeader + t.lights.capacity() * sizeof(std::uint32_t) +
                 t.probability.capacity() * sizeof(double);
    return total;
}

}  // namespace omis
