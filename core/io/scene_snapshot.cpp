#include "io/scene_snapshot.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

#include "lights/environment_map.h"
#include "render/scene.h"

namespace omis {

// A Light is written field by field (write_light / read_light). A new field
// changes its size: add the field to both (at the end of the record, which
// states its length, so older files still load) and then update this size.
// Light::environment (an image world's map) is the WMAP section.
static_assert(sizeof(Light) == 512,
              "Light changed: write its new fields in scene_snapshot.cpp (write_light, "
              "read_light), then update this size");

namespace {

constexpr char kMagic[8] = {'O', 'M', 'I', 'S', 'S', 'N', 'A', 'P'};
constexpr std::uint32_t kSectionRequired = 1;
constexpr std::size_t kHeaderBytes = 16, kEntryBytes = 32;

constexpr std::uint32_t tag(const char (&name)[5]) {
    return std::uint32_t(std::uint8_t(name[0])) | std::uint32_t(std::uint8_t(name[1])) << 8 |
           std::uint32_t(std::uint8_t(name[2])) << 16 | std::uint32_t(std::uint8_t(name[3])) << 24;
}
const std::uint32_t kOptions = tag("OPTS"), kGeometry = tag("GEOM"), kReceivers = tag("RECV"),
                    kLights = tag("LITE"), kWorldMap = tag("WMAP");

std::string tag_name(std::uint32_t t) {
    std::string s(4, '?');
    for (int i = 0; i < 4; ++i) {
        const char c = char((t >> (8 * i)) & 0xff);
        if (c >= 0x20 && c < 0x7f) s[i] = c;
    }
    return s;
}

// ---- Writing ---------------------------------------------------------------

struct Writer {
    std::vector<unsigned char> bytes;

    void u8(std::uint8_t v) { bytes.push_back(v); }
    void u32(std::uint32_t v) {
        for (int i = 0; i < 4; ++i) bytes.push_back(std::uint8_t(v >> (8 * i)));
    }
    void u64(std::uint64_t v) {
        for (int i = 0; i < 8; ++i) bytes.push_back(std::uint8_t(v >> (8 * i)));
    }
    void f64(double v) {
        std::uint64_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        u64(bits);
    }
    void vec(const Vec3& v) { f64(v.x), f64(v.y), f64(v.z); }
    void text(const std::string& s) {
        u32(std::uint32_t(s.size()));
        bytes.insert(bytes.end(), s.begin(), s.end());
    }
};

struct Section {
    std::uint32_t tag, flags;
    std::vector<unsigned char> bytes;
};

Section options_section(const Scene& scene) {
    Writer w;
    w.u32(scene.mesh_lights_enabled() ? 1 : 0);
    return {kOptions, kSectionRequired, std::move(w.bytes)};
}

Section geometry_section(const Scene& scene) {
    Writer w;
    const std::vector<Mesh>& meshes = scene.geometry().meshes();
    w.u32(std::uint32_t(meshes.size()));
    for (const Mesh& m : meshes) {
        w.text(m.name);
        w.u64(m.positions.size());
        w.u64(m.triangles.size());
        w.u8(m.has_normals()), w.u8(m.has_uvs()), w.u8(m.is_emissive()), w.u8(0);
        for (const Vec3& p : m.positions) w.vec(p);
        for (const auto& t : m.triangles) w.u32(t[0]), w.u32(t[1]), w.u32(t[2]);
        for (const Vec3& n : m.corner_normals) w.vec(n);
        for (const auto& uv : m.corner_uvs) w.f64(uv[0]), w.f64(uv[1]);
        if (m.is_emissive()) w.vec(*m.emission);
    }
    return {kGeometry, kSectionRequired, std::move(w.bytes)};
}

Section receivers_section(const Scene& scene) {
    Writer w;
    const std::size_t meshes = scene.geometry().num_meshes();
    w.u32(std::uint32_t(meshes));
    for (std::uint32_t m = 0; m < meshes; ++m) {
        const Receiver& r = scene.mesh_receiver(m);
        w.u32(std::uint32_t(r.model));
        w.f64(r.roughness);
    }
    return {kReceivers, kSectionRequired, std::move(w.bytes)};
}

// The doubles of a light record, in file order (read_light reads them back
// in the same order).
template <class Visit>
void light_doubles(Light& l, Visit&& visit) {
    auto v3 = [&](Vec3& v) { visit(v.x), visit(v.y), visit(v.z); };
    v3(l.emission);
    visit(l.spread);
    v3(l.triangle.p0), v3(l.triangle.p1), v3(l.triangle.p2);
    visit(l.triangle_area);
    v3(l.rect.corner), v3(l.rect.edge_u), v3(l.rect.edge_v);
    v3(l.ellipse.center), v3(l.ellipse.axis_a), v3(l.ellipse.axis_b);
    Light::SpreadConstants& s = l.spread_constants;
    visit(s.tan_half), visit(s.cot_half), visit(s.one_minus_b_cot_b);
    v3(s.unit_normal);
    visit(s.length1), visit(s.length2);
    v3(l.position);
    visit(l.radius), visit(l.mesh_area);
    v3(l.spot_axis);
    visit(l.spot_cos_half), visit(l.spot_smooth);
    v3(l.to_sun);
    visit(l.sun_half_angle);
}
constexpr std::uint32_t kLightDoubles = 54;

// The lights as they were added: after commit, the analytic ones (commit
// appends mesh and emissive-triangle lights, which a load's commit makes again).
Section lights_section(const Scene& scene) {
    Writer w;
    const std::size_t count = scene.committed() ? scene.num_analytic_lights() : scene.lights().size();
    w.u32(std::uint32_t(count));
    for (std::size_t i = 0; i < count; ++i) {
        Light l = scene.lights()[i];
        w.u32(std::uint32_t(l.type));
        w.u32(std::uint32_t(l.two_sided) | std::uint32_t(l.cast_shadow) << 1 |
              std::uint32_t(l.visible_to_bsdf) << 2);
        w.u32(kLightDoubles);
        std::uint32_t n = 0;
        light_doubles(l, [&](double& x) { w.f64(x), ++n; });
        if (n != kLightDoubles) throw std::logic_error("snapshot: light record miscounted");
    }
    return {kLights, kSectionRequired, std::move(w.bytes)};
}

// The world light's image (environment_map.h), when it has one: its size,
// rotation, compensation and texels (float RGB, rows top first). The light
// record in LITE keeps its flags; the map is attached to it on load. A scene
// without an image world writes no such section.
const Light* image_world(const Scene& scene) {
    const std::size_t count =
        scene.committed() ? scene.num_analytic_lights() : scene.lights().size();
    for (std::size_t i = 0; i < count; ++i)
        if (scene.lights()[i].type == LightType::World && scene.lights()[i].environment)
            return &scene.lights()[i];
    return nullptr;
}

Section world_map_section(const EnvironmentMap& map) {
    Writer w;
    w.u32(std::uint32_t(map.width())), w.u32(std::uint32_t(map.height()));
    w.u32(map.compensated() ? 1 : 0);
    w.vec(map.rotation());
    for (float x : map.rgb()) {
        std::uint32_t bits;
        std::memcpy(&bits, &x, sizeof bits);
        w.u32(bits);
    }
    return {kWorldMap, kSectionRequired, std::move(w.bytes)};
}

// ---- Reading ---------------------------------------------------------------

// Bounded reads from one section: every read checks what is left first, and
// every count is checked against what is left before anything is allocated.
class Reader {
public:
    Reader(const unsigned char* data, std::size_t size, std::string where)
        : p_(data), end_(data + size), where_(std::move(where)) {}

    std::size_t left() const { return std::size_t(end_ - p_); }
    void need(std::size_t bytes, const char* what) const {
        if (bytes > left())
            throw SnapshotError("snapshot: " + where_ + " is truncated (" + what + ")");
    }
    // A count of items of at least `item_bytes` each: refused when they
    // could not all be in what is left (a corrupted or hostile count).
    std::uint64_t count(std::uint64_t n, std::size_t item_bytes, const char* what) const {
        if (item_bytes > 0 && n > left() / item_bytes)
            throw SnapshotError("snapshot: " + where_ + ": " + what + " count " + std::to_string(n) +
                                " does not fit in the " + std::to_string(left()) + " bytes left");
        return n;
    }
    std::uint8_t u8(const char* what) {
        need(1, what);
        return *p_++;
    }
    std::uint32_t u32(const char* what) {
        need(4, what);
        std::uint32_t v = 0;
        for (int i = 0; i < 4; ++i) v |= std::uint32_t(p_[i]) << (8 * i);
        p_ += 4;
        return v;
    }
    std::uint64_t u64(const char* what) {
        need(8, what);
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= std::uint64_t(p_[i]) << (8 * i);
        p_ += 8;
        return v;
    }
    double f64(const char* what) {
        const std::uint64_t bits = u64(what);
        double v;
        std::memcpy(&v, &bits, sizeof v);
        return v;
    }
    Vec3 vec(const char* what) {
        const double x = f64(what), y = f64(what), z = f64(what);
        return {x, y, z};
    }
    std::string text(const char* what) {
        const std::uint64_t n = count(u32(what), 1, what);
        std::string s(reinterpret_cast<const char*>(p_), std::size_t(n));
        p_ += n;
        return s;
    }
    void skip(std::size_t bytes, const char* what) {
        need(bytes, what);
        p_ += bytes;
    }
    const std::string& where() const { return where_; }

private:
    const unsigned char* p_;
    const unsigned char* end_;
    std::string where_;
};

void read_options(Reader r, Scene& scene) {
    const std::uint32_t flags = r.u32("mesh lights");
    scene.set_mesh_lights((flags & 1) != 0);
}

// Rows of doubles from the file, for MeshInput (which copies and validates).
std::vector<double> read_doubles(Reader& r, std::uint64_t n, const char* what) {
    std::vector<double> out(std::size_t(r.count(n, 8, what)));
    for (double& x : out) x = r.f64(what);
    return out;
}

void read_mesh(Reader& r, Scene& scene) {
    MeshInput in;
    in.name = r.text("mesh name");
    const std::uint64_t V = r.count(r.u64("vertex count"), 24, "vertex");
    const std::uint64_t T = r.count(r.u64("triangle count"), 12, "triangle");
    const bool normals = r.u8("flags"), uvs = r.u8("flags"), emissive = r.u8("flags");
    r.u8("flags");
    const std::vector<double> positions = read_doubles(r, 3 * V, "vertex");
    std::vector<std::uint32_t> triangles(std::size_t(r.count(3 * T, 4, "triangle")));
    for (std::uint32_t& i : triangles) i = r.u32("triangle");
    const std::vector<double> corner_normals =
        normals ? read_doubles(r, 9 * T, "corner normal") : std::vector<double>();
    const std::vector<double> corner_uvs =
        uvs ? read_doubles(r, 6 * T, "corner uv") : std::vector<double>();
    in.positions = ScalarArray::of(positions.data(), V, 3);
    in.triangles = {triangles.data(), std::size_t(T), 3};
    if (normals) in.normals = ScalarArray::of(corner_normals.data(), 3 * T, 3);
    if (uvs) in.uvs = ScalarArray::of(corner_uvs.data(), 3 * T, 2);
    if (emissive) in.emission = r.vec("emission");
    scene.add_mesh(in);  // validates: indices in range, finite values
}

void read_geometry(Reader r, Scene& scene) {
    const std::uint32_t meshes = r.u32("mesh count");
    r.count(meshes, 16, "mesh");
    for (std::uint32_t m = 0; m < meshes; ++m) read_mesh(r, scene);
}

void read_receivers(Reader r, Scene& scene) {
    const std::uint32_t meshes = std::uint32_t(r.count(r.u32("receiver count"), 12, "receiver"));
    if (meshes != scene.geometry().num_meshes())
        throw SnapshotError("snapshot: " + r.where() + " lists " + std::to_string(meshes) +
                            " receivers for " + std::to_string(scene.geometry().num_meshes()) +
                            " meshes");
    for (std::uint32_t m = 0; m < meshes; ++m) {
        const std::uint32_t model = r.u32("receiver model");
        const double roughness = r.f64("receiver roughness");
        if (model > std::uint32_t(ReceiverModel::OrenNayar))
            throw SnapshotError("snapshot: " + r.where() + ": unknown receiver model " +
                                std::to_string(model) + " for mesh " + std::to_string(m));
        scene.set_mesh_receiver(m, make_receiver(ReceiverModel(model), roughness));
    }
}

Light read_light(Reader& r, std::uint32_t index) {
    const std::string who = r.where() + ": light " + std::to_string(index);
    Light l;
    const std::uint32_t type = r.u32("light type");
    // Mesh lights and emissive triangles are made by commit, never stored.
    if (type >= std::uint32_t(kLightTypes) || type == std::uint32_t(LightType::Mesh) ||
        type == std::uint32_t(LightType::Triangle))
        throw SnapshotError("snapshot: " + who + " has an unknown type " + std::to_string(type));
    l.type = LightType(type);
    const std::uint32_t flags = r.u32("light flags");
    l.two_sided = flags & 1, l.cast_shadow = (flags >> 1) & 1, l.visible_to_bsdf = (flags >> 2) & 1;
    const std::uint32_t n = std::uint32_t(r.count(r.u32("light fields"), 8, "light field"));
    if (n < kLightDoubles)
        throw SnapshotError("snapshot: " + who + " has " + std::to_string(n) + " fields, " +
                            std::to_string(kLightDoubles) + " expected");
    light_doubles(l, [&](double& x) {
        x = r.f64("light field");
        if (!std::isfinite(x)) throw SnapshotError("snapshot: " + who + " has a value that is not finite");
    });
    r.skip(std::size_t(n - kLightDoubles) * 8, "light field");  // fields of a later version
    if (l.emission.x < 0 || l.emission.y < 0 || l.emission.z < 0)
        throw SnapshotError("snapshot: " + who + " has a negative emission");
    return l;
}

void read_lights(Reader r, Scene& scene) {
    const std::uint32_t count = std::uint32_t(r.count(r.u32("light count"), 12, "light"));
    for (std::uint32_t i = 0; i < count; ++i) scene.add_light(read_light(r, i));
}

// After LITE: the map replaces the world light read there (Scene::add_light
// replaces a world), keeping its flags. EnvironmentMap validates the texels.
void read_world_map(Reader r, Scene& scene) {
    const Light* world = nullptr;
    for (const Light& l : scene.lights())
        if (l.type == LightType::World) world = &l;
    if (!world) throw SnapshotError("snapshot: " + r.where() + " has no world light to go with");
    const std::uint32_t width = r.u32("map width"), height = r.u32("map height");
    if (width == 0 || height == 0 || width > 65536 || height > 65536)
        throw SnapshotError("snapshot: " + r.where() + ": map size " + std::to_string(width) +
                            " x " + std::to_string(height) + " is out of range");
    const bool compensate = (r.u32("map flags") & 1) != 0;
    const Vec3 rotation = r.vec("map rotation");
    if (!isfinite(rotation)) throw SnapshotError("snapshot: " + r.where() + ": rotation is not finite");
    std::vector<float> rgb(std::size_t(r.count(3ull * width * height, 4, "map texel")));
    for (float& x : rgb) {
        const std::uint32_t bits = r.u32("map texel");
        std::memcpy(&x, &bits, sizeof x);
    }
    Light l = make_environment_light(std::make_shared<const EnvironmentMap>(
        std::move(rgb), int(width), int(height), rotation, compensate));
    l.two_sided = world->two_sided, l.cast_shadow = world->cast_shadow;
    l.visible_to_bsdf = world->visible_to_bsdf;
    scene.add_light(l);
}

// ---- The container ---------------------------------------------------------

struct Entry {
    std::uint32_t tag = 0, flags = 0;
    std::uint64_t offset = 0, size = 0;
    std::uint32_t crc = 0;
};

std::vector<Entry> read_table(const unsigned char* data, std::size_t size) {
    if (size < kHeaderBytes)
        throw SnapshotError("snapshot: the file is truncated (" + std::to_string(size) +
                            " bytes, shorter than the header)");
    if (std::memcmp(data, kMagic, sizeof kMagic) != 0)
        throw SnapshotError("snapshot: not an omis scene snapshot (wrong magic bytes)");
    Reader header(data + 8, 8, "header");
    const std::uint32_t version = header.u32("version");
    if (version != kSnapshotVersion)
        throw SnapshotError("snapshot: format version " + std::to_string(version) +
                            " is not supported (this omis reads version " +
                            std::to_string(kSnapshotVersion) + ")");
    const std::uint32_t sections = header.u32("section count");
    if (sections > kMostSnapshotSections)
        throw SnapshotError("snapshot: the header lists " + std::to_string(sections) +
                            " sections (at most " + std::to_string(kMostSnapshotSections) + ")");
    const std::size_t table_end = kHeaderBytes + std::size_t(sections) * kEntryBytes;
    if (table_end + 4 > size) throw SnapshotError("snapshot: the file is truncated (section table)");
    Reader table(data + kHeaderBytes, table_end + 4 - kHeaderBytes, "section table");
    std::vector<Entry> entries(sections);
    for (Entry& e : entries) {
        e.tag = table.u32("tag"), e.flags = table.u32("flags");
        e.offset = table.u64("offset"), e.size = table.u64("size");
        e.crc = table.u32("checksum");
        table.u32("reserved");
    }
    if (table.u32("checksum") != crc32(data, table_end))
        throw SnapshotError("snapshot: the header or section table is corrupted (checksum mismatch)");
    for (const Entry& e : entries) {
        const std::string who = "section " + tag_name(e.tag);
        if (e.offset > size || e.size > size - e.offset)
            throw SnapshotError("snapshot: the file is truncated (" + who + " ends at byte " +
                                std::to_string(e.offset + e.size) + " of " + std::to_string(size) +
                                ")");
        if (crc32(data + e.offset, std::size_t(e.size)) != e.crc)
            throw SnapshotError("snapshot: " + who + " is corrupted (checksum mismatch)");
    }
    return entries;
}

void require_empty(const Scene& scene) {
    if (scene.committed() || scene.geometry().num_meshes() > 0 || !scene.lights().empty())
        throw std::logic_error("snapshot: load into a new scene (no meshes, lights or commit)");
}

}  // namespace

std::uint32_t crc32(const unsigned char* data, std::size_t size) {
    static const std::array<std::uint32_t, 256> table = [] {
        std::array<std::uint32_t, 256> t{};
        for (std::uint32_t i = 0; i < 256; ++i) {
            std::uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            t[i] = c;
        }
        return t;
    }();
    std::uint32_t c = 0xFFFFFFFFu;
    for (std::size_t i = 0; i < size; ++i) c = table[(c ^ data[i]) & 0xff] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

std::vector<unsigned char> save_snapshot(const Scene& scene) {
    std::vector<Section> sections = {options_section(scene), geometry_section(scene),
                                     receivers_section(scene), lights_section(scene)};
    if (const Light* world = image_world(scene))
        sections.push_back(world_map_section(*world->environment));
    Writer w;
    w.bytes.insert(w.bytes.end(), kMagic, kMagic + sizeof kMagic);
    w.u32(kSnapshotVersion);
    w.u32(std::uint32_t(sections.size()));
    std::uint64_t offset = kHeaderBytes + sections.size() * kEntryBytes + 4;
    for (const Section& s : sections) {
        w.u32(s.tag), w.u32(s.flags), w.u64(offset), w.u64(s.bytes.size());
        w.u32(crc32(s.bytes.data(), s.bytes.size())), w.u32(0);
        offset += s.bytes.size();
    }
    w.u32(crc32(w.bytes.data(), w.bytes.size()));
    for (const Section& s : sections) w.bytes.insert(w.bytes.end(), s.bytes.begin(), s.bytes.end());
    return std::move(w.bytes);
}

void save_snapshot(const Scene& scene, const std::string& path) {
    const std::vector<unsigned char> bytes = save_snapshot(scene);
    // A temporary file beside the destination, renamed over it: a failed
    // write leaves an existing snapshot as it was.
    const std::string tmp = path + ".omis-" + std::to_string(::getpid()) + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error("snapshot: cannot write '" + path + "'");
        out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        out.flush();
        if (!out) {
            std::remove(tmp.c_str());
            throw std::runtime_error("snapshot: writing '" + path + "' failed (disk full?)");
        }
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw std::runtime_error("snapshot: cannot replace '" + path + "'");
    }
}

void load_snapshot(const unsigned char* data, std::size_t size, Scene& scene) {
    require_empty(scene);
    const std::vector<Entry> entries = read_table(data, size);
    using ReadSection = void (*)(Reader, Scene&);
    // In the order a scene is built: receivers name meshes, lights follow.
    struct Known {
        std::uint32_t tag;
        ReadSection read;
        bool optional;
    };
    const Known known[] = {{kOptions, read_options, false},   {kGeometry, read_geometry, false},
                           {kReceivers, read_receivers, false}, {kLights, read_lights, false},
                           {kWorldMap, read_world_map, true}};
    for (const Entry& e : entries) {
        const bool is_known = std::any_of(std::begin(known), std::end(known),
                                          [&](const Known& k) { return k.tag == e.tag; });
        if (!is_known && (e.flags & kSectionRequired))
            throw SnapshotError("snapshot: section " + tag_name(e.tag) +
                                " is required but unknown here (made by a newer omis?)");
    }
    for (const auto& [t, read, optional] : known) {
        const Entry* found = nullptr;
        for (const Entry& e : entries)
            if (e.tag == t) {
                if (found) throw SnapshotError("snapshot: section " + tag_name(t) + " appears twice");
                found = &e;
            }
        if (!found && optional) continue;
        if (!found) throw SnapshotError("snapshot: section " + tag_name(t) + " is missing");
        read(Reader(data + found->offset, std::size_t(found->size), "section " + tag_name(t)), scene);
    }
    scene.commit();
}

void load_snapshot(const std::string& path, Scene& scene) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("snapshot: cannot open '" + path + "'");
    const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                           std::istreambuf_iterator<char>());
    if (in.bad()) throw std::runtime_error("snapshot: cannot read '" + path + "'");
    load_snapshot(bytes.data(), bytes.size(), scene);
}

}  // namespace omis
