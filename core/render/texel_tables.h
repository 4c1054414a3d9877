// What a bake works out per texel before its first sample and needs again at
// every later pass: which techniques take part there and, for the light
// techniques that draw from a per-texel table (`unoccluded`, and `uniform` /
// `power` among few lights), the table. These depend on the texel alone
// (its footprint's probes), not on the pass, so they are kept from pass to
// pass instead of recomputed: a spread light's weights (SPEC §3's spread-
// weighted irradiance at up to five probes) cost more than a one-round pass's
// samples. A table kept is the one recomputation would give, bit for bit.
// Texels whose light techniques all draw from selectors keep only which
// techniques take part, and only in a slot of their own (index_points); bakes
// whose tables need no irradiance (`uniform`, `power`: point_setup.cpp,
// cheap_tables_) keep nothing.
//
// Shared by the threads of one lighting job: a texel is shaded by one thread
// at a time, and entries are only added, never changed or removed. Memory is
// capped (byte_budget); texels past the cap recompute their tables.
#pragma once

#include <tbb/concurrent_unordered_map.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace omis {

class TexelTables {
public:
    static constexpr std::size_t kDefaultByteBudget = std::size_t(64) << 20;

    // One light technique's table: lights and their probabilities.
    struct Table {
        int technique = 0;
        std::vector<std::uint32_t> lights;
        std::vector<double> probability;
    };
    struct Entry {
        std::uint64_t mask = 0, light_mask = 0;  // active techniques (bit k)
        std::vector<Table> tables;               // table techniques only
    };

    explicit TexelTables(std::size_t byte_budget = kDefaultByteBudget) : budget_(byte_budget) {}
    TexelTables(const TexelTables&) = delete;
    TexelTables& operator=(const TexelTables&) = delete;

    // Points (streams) 0 … count − 1 get a slot each in an array instead of
    // a node of the hash map: no hashing, no node to allocate, a cheap
    // clear — a bake's first pass keeps every texel's entry. Only while the
    // array stays within a quarter of the byte budget (else the map, which
    // holds only the points that keep something). Call before any keep.
    void index_points(std::size_t count);
    // Whether `texel` has a slot of its own (index_points): an entry without
    // tables costs no bytes there.
    bool has_slot(std::uint64_t texel) const { return texel < indexed_count_; }
    // The entry kept for `texel`, or null.
    const Entry* find(std::uint64_t texel) const;
    // Keeps `entry` for `texel` unless one is kept already or the budget is
    // spent.
    void keep(std::uint64_t texel, Entry&& entry);
    std::size_t bytes() const { return bytes_.load(std::memory_order_relaxed); }
    std::size_t size() const { return entries_.size() + indexed_kept_.load(std::memory_order_relaxed); }

private:
    static std::size_t bytes_of(const Entry& entry);
    bool reserve(std::size_t size);
    struct Slot {
        std::atomic<bool> kept{false};
        Entry entry;
    };
    std::unique_ptr<Slot[]> indexed_;
    std::size_t indexed_count_ = 0;
    std::atomic<std::size_t> indexed_kept_{0};
    tbb::concurrent_unordered_map<std::uint64_t, Entry> entries_;
    std::atomic<std::size_t> bytes_{0};
    std::size_t budget_;
};

}  // namespace omis
