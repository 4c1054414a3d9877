// Scene snapshots: everything a bake reads from a Scene, in one versioned,
// self-describing file, so that a scene built on an artist's machine can be
// baked elsewhere (the command line, a farm) with the same bits.
//
// Layout (all integers little-endian, doubles IEEE-754 binary64):
//
//   header   8 bytes  magic "OMISSNAP"
//            u32      format version (kSnapshotVersion)
//            u32      section count S (at most kMostSnapshotSections)
//   table    S × 32 bytes: u32 tag (four ASCII characters), u32 flags
//            (bit 0: required), u64 offset, u64 size, u32 CRC-32 of the
//            section's bytes, u32 reserved (0)
//            u32      CRC-32 of the header and the table
//   payload  the sections, at their offsets
//
// Sections of version 1 (scene_snapshot.cpp writes and reads each):
//   OPTS  scene options (mesh lights on/off)
//   GEOM  meshes: name, positions, triangles, corner normals and UVs, emission
//   RECV  each mesh's receiver closure (model, roughness)
//   LITE  the lights as added (before commit's emissive-triangle lights):
//         each a record whose length it states, so later fields can follow
//   WMAP  only with an image world: the world light's map (u32 width, height,
//         compensation flag; rotation; width × height × 3 float texels, rows
//         top first), attached to LITE's world light on load
//
// A reader skips a section it does not know unless the section is marked
// required: a writer marks required every section a bake's bits depend on,
// and an older reader then refuses the file ("made by a newer omis") instead
// of baking something else. Adding a section (as WMAP was):
// pick a new tag, write it in save_snapshot with
// kSectionRequired when bakes read it, read it in load_snapshot
// (absent in older files: keep the scene's default), and add a test; the
// version number changes only when an existing section's layout does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace omis {

class Scene;

constexpr std::uint32_t kSnapshotVersion = 1;
// Sections a file may list: a bound on the table read before any checksum.
constexpr std::uint32_t kMostSnapshotSections = 1024;

// Every problem with a snapshot's bytes (truncated, corrupted, wrong version,
// counts that do not fit the file): the message names the file part.
struct SnapshotError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// The snapshot of a scene (committed or not) as bytes.
std::vector<unsigned char> save_snapshot(const Scene& scene);
// Writes it to `path` atomically (a temporary file renamed over it); throws
// std::runtime_error naming the path when the file cannot be written.
void save_snapshot(const Scene& scene, const std::string& path);

// Fills `scene` (new: no meshes or lights, not committed) from a snapshot and
// commits it. Throws SnapshotError for bytes that are not a sound snapshot,
// std::invalid_argument when a value is refused as the scene's setters refuse
// it. Every allocation is bounded by the bytes actually present.
void load_snapshot(const unsigned char* data, std::size_t size, Scene& scene);
void load_snapshot(const std::string& path, Scene& scene);

// CRC-32 (IEEE 802.3, as zlib's crc32) of `size` bytes.
std::uint32_t crc32(const unsigned char* data, std::size_t size);

}  // namespace omis
