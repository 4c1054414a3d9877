// Image writers: EXR round trip (exact floats, names, row order), PNG through
// Blender's view transforms (reference values saved by Blender 3.4.1 itself),
// argument errors, and atomicity (failures leave the destination untouched and
// no temporary files behind).
#include <OpenImageIO/imageio.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/image_io.h"

namespace fs = std::filesystem;
using namespace omis;

namespace {

// A fresh directory under the system temp dir, removed with its contents.
struct TempDir {
    fs::path path;
    TempDir() {
        std::string templ = (fs::temp_directory_path() / "omis-io-test-XXXXXX").string();
        if (!::mkdtemp(templ.data())) throw std::runtime_error("mkdtemp failed");
        path = templ;
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
    std::string operator/(const std::string& name) const { return (path / name).string(); }
    std::vector<std::string> entries() const {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(path)) {
            names.push_back(e.path().filename().string());
        }
        std::sort(names.begin(), names.end());
        return names;
    }
};

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

struct Png {
    int width = 0, height = 0, channels = 0;
    std::vector<unsigned char> pixels;  // file order: top row first
    int at(int x, int file_row, int c) const {
        return pixels[(std::size_t(file_row) * width + x) * channels + c];
    }
};

Png read_png(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    Png png;
    png.width = in->spec().width;
    png.height = in->spec().height;
    png.channels = in->spec().nchannels;
    png.pixels.resize(std::size_t(png.width) * png.height * png.channels);
    REQUIRE(in->read_image(0, 0, 0, png.channels, OIIO::TypeDesc::UINT8,
                           png.pixels.data()));
    return png;
}

// One grey pixel per value, a single row.
std::vector<float> grey_row(const std::vector<float>& values) {
    std::vector<float> rgb;
    for (float v : values) rgb.insert(rgb.end(), {v, v, v});
    return rgb;
}

std::vector<int> png_greys(const std::string& path, const std::vector<float>& values,
                           const DisplaySettings& settings) {
    write_png(path, int(values.size()), 1, grey_row(values).data(), settings);
    Png png = read_png(path);
    std::vector<int> out;
    for (int x = 0; x < png.width; ++x) out.push_back(png.at(x, 0, 0));
    return out;
}

bool have_blender_config() {
    if (!find_blender_ocio_config().empty()) return true;
    WARN("Blender's OCIO config not found: view-transform checks skipped");
    return false;
}

// Limits file size for this process (writes past it fail with EFBIG), and
// ignores the SIGXFSZ that would otherwise kill it; both restored on exit.
struct FileSizeLimit {
    rlimit old_limit{};
    struct sigaction old_action {};
    explicit FileSizeLimit(rlim_t bytes) {
        struct sigaction ignore {};
        ignore.sa_handler = SIG_IGN;
        sigaction(SIGXFSZ, &ignore, &old_action);
        getrlimit(RLIMIT_FSIZE, &old_limit);
        rlimit limit = old_limit;
        limit.rlim_cur = bytes;
        setrlimit(RLIMIT_FSIZE, &limit);
    }
    ~FileSizeLimit() {
        setrlimit(RLIMIT_FSIZE, &old_limit);
        sigaction(SIGXFSZ, &old_action, nullptr);
    }
};

// Incompressible data, so that files are large whatever the compression.
ImageChannels noise_image(int w, int h, const std::vector<std::string>& names) {
    ImageChannels img{w, h, names, {}};
    std::uint32_t s = 12345;
    for (std::size_t i = 0; i < std::size_t(w) * h * names.size(); ++i) {
        s = s * 1664525u + 1013904223u;
        img.pixels.push_back(float(s) / 4294967296.0f);
    }
    return img;
}

}  // namespace

TEST_CASE("EXR round trip: float channels, names, bottom row first", "[io]") {
    TempDir dir;
    const std::string path = dir / "bake.exr";
    const int w = 7, h = 5;
    const std::vector<std::string> names{"R", "G", "B", "noise", "mask"};
    ImageChannels img{w, h, names, {}};
    // Values half floats cannot hold, distinct per pixel and channel.
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 5; ++c)
                img.pixels.push_back(float(c * 1000 + y * 10 + x) + 1.0f / 3.0f +
                                     (c == 3 ? 1e-7f : 0.0f));
    write_exr(path, img);
    CHECK(dir.entries() == std::vector<std::string>{"bake.exr"});

    auto in = OIIO::ImageInput::open(path);
    REQUIRE(in);
    const OIIO::ImageSpec& spec = in->spec();
    REQUIRE(spec.width == w);
    REQUIRE(spec.height == h);
    REQUIRE(spec.nchannels == 5);
    CHECK(spec.format == OIIO::TypeDesc::FLOAT);
    for (const OIIO::TypeDesc& f : spec.channelformats) CHECK(f == OIIO::TypeDesc::FLOAT);
    CHECK(spec.get_string_attribute("compression") == "zip");
    CHECK(std::string(spec.get_string_attribute("Software")).rfind("omis ", 0) == 0);
    std::vector<std::string> file_names = spec.channelnames;
    std::vector<std::string> sorted_names = names;
    std::sort(file_names.begin(), file_names.end());
    std::sort(sorted_names.begin(), sorted_names.end());
    REQUIRE(file_names == sorted_names);

    std::vector<float> file(std::size_t(w) * h * 5);
    REQUIRE(in->read_image(0, 0, 0, 5, OIIO::TypeDesc::FLOAT, file.data()));
    // EXR keeps its own channel order: compare by name.
    for (int fc = 0; fc < 5; ++fc) {
        const int c = int(std::find(names.begin(), names.end(), spec.channelnames[fc]) -
                          names.begin());
        for (int file_row = 0; file_row < h; ++file_row) {
            const int y = h - 1 - file_row;  // the file's first scanline is the top row
            for (int x = 0; x < w; ++x) {
                INFO("channel " << names[c] << " x " << x << " y " << y);
                CHECK(file[(std::size_t(file_row) * w + x) * 5 + fc] ==
                      img.pixels[(std::size_t(y) * w + x) * 5 + c]);
            }
        }
    }
}

TEST_CASE("EXR rejects inconsistent images before touching the file", "[io]") {
    TempDir dir;
    const std::string path = dir / "bake.exr";
    write_bytes(path, "previous contents");
    ImageChannels img{2, 2, {"R", "G", "B"}, std::vector<float>(11, 0.5f)};
    CHECK_THROWS_AS(write_exr(path, img), std::invalid_argument);
    img.pixels.resize(12);
    img.names = {"R", "G", "R"};
    CHECK_THROWS_WITH(write_exr(path, img), Catch::Contains("appears twice"));
    img.names = {"R", "G", "B"};
    img.width = 0;
    CHECK_THROWS_AS(write_exr(path, img), std::invalid_argument);
    CHECK(read_bytes(path) == "previous contents");
    CHECK(dir.entries() == std::vector<std::string>{"bake.exr"});
}

TEST_CASE("PNG Standard view is the sRGB encoding, bottom row first", "[io]") {
    TempDir dir;
    const std::string path = dir / "ramp.png";
    // Two rows: bottom row (buffer row 0) red-ish, top row greys 0, 0.5, 1.
    const std::vector<float> rgb{0.2f, 0.0f, 0.0f, 0.2f, 0.0f, 0.0f, 0.2f, 0.0f, 0.0f,
                                 0.0f, 0.0f, 0.0f, 0.5f, 0.5f, 0.5f, 1.0f, 1.0f, 1.0f};
    write_png(path, 3, 2, rgb.data(), DisplaySettings{});
    Png png = read_png(path);
    REQUIRE(png.width == 3);
    REQUIRE(png.height == 2);
    REQUIRE(png.channels == 3);
    // File row 0 is the top row = buffer row 1.
    for (int c = 0; c < 3; ++c) {
        CHECK(png.at(0, 0, c) == 0);
        CHECK(png.at(1, 0, c) == Approx(188).margin(1));  // sRGB(0.5) = 0.7354
        CHECK(png.at(2, 0, c) == 255);
    }
    CHECK(png.at(0, 1, 0) == Approx(124).margin(1));  // sRGB(0.2) = 0.4845
    CHECK(png.at(0, 1, 1) == 0);
    CHECK(dir.entries() == std::vector<std::string>{"ramp.png"});

    // Standard follows the sRGB OETF over the whole range (Blender's LUT is an
    // approximation of it); values past 1, negative values and NaN clamp.
    std::vector<float> values;
    for (int i = 0; i <= 64; ++i) values.push_back(float(i) / 64.0f);
    values.insert(values.end(), {-1.0f, 7.0f, std::nanf("")});
    const std::vector<int> got = png_greys(path, values, DisplaySettings{});
    for (int i = 0; i <= 64; ++i) {
        const double v = values[i];
        const double srgb = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
        INFO("linear " << v);
        CHECK(got[i] == Approx(255 * srgb).margin(1));
    }
    CHECK(got[65] == 0);
    CHECK(got[66] == 255);
    CHECK(got[67] == 0);

    // Exposure is in stops in scene linear: +1 stop turns 0.25 into sRGB(0.5).
    DisplaySettings brighter;
    brighter.exposure = 1;
    CHECK(png_greys(path, {0.25f}, brighter)[0] == Approx(188).margin(1));
}

TEST_CASE("PNG Filmic matches Blender 3.4.1", "[io]") {
    if (!have_blender_config()) return;
    TempDir dir;
    const std::string path = dir / "filmic.png";
    // Saved by Blender 3.4.1 (Image.save_render, 8-bit RGB PNG) from the same
    // linear greys with each view setting.
    const std::vector<float> values{0.0f, 0.01f, 0.05f, 0.18f, 0.5f, 1.0f, 2.0f, 8.0f, 16.0f};
    const std::vector<int> blender_filmic{0, 26, 70, 128, 177, 206, 228, 251, 255};
    const std::vector<int> blender_filmic_high_contrast{0, 13, 55, 128, 190, 220, 239, 253, 255};

    DisplaySettings standard;
    DisplaySettings filmic;
    filmic.view = "Filmic";
    const std::vector<int> s = png_greys(path, values, standard);
    const std::vector<int> f = png_greys(path, values, filmic);
    CHECK(s[5] == 255);
    CHECK(f[5] != s[5]);  // Filmic keeps headroom above 1
    CHECK(f[5] < 230);
    // Filmic puts middle grey near the middle of the display range.
    CHECK(f[3] >= 118);
    CHECK(f[3] <= 138);
    for (std::size_t i = 0; i < values.size(); ++i) {
        INFO("linear " << values[i]);
        CHECK(f[i] == Approx(blender_filmic[i]).margin(1));
    }
    filmic.look = "High Contrast";
    const std::vector<int> hc = png_greys(path, values, filmic);
    for (std::size_t i = 0; i < values.size(); ++i) {
        INFO("linear " << values[i]);
        CHECK(hc[i] == Approx(blender_filmic_high_contrast[i]).margin(1));
    }
}

TEST_CASE("PNG rejects unknown views, displays and looks, listing the known ones", "[io]") {
    if (!have_blender_config()) return;
    TempDir dir;
    const std::string path = dir / "x.png";
    const std::vector<float> rgb(3, 0.5f);
    DisplaySettings settings;
    settings.view = "Flimic";
    CHECK_THROWS_AS(write_png(path, 1, 1, rgb.data(), settings), std::invalid_argument);
    CHECK_THROWS_WITH(write_png(path, 1, 1, rgb.data(), settings),
                      Catch::Contains("unknown view 'Flimic'") &&
                          Catch::Contains("'Standard'") && Catch::Contains("'Filmic'") &&
                          Catch::Contains("'Filmic Log'"));
    settings = DisplaySettings{};
    settings.display = "Rec.2020";
    CHECK_THROWS_WITH(write_png(path, 1, 1, rgb.data(), settings),
                      Catch::Contains("unknown display 'Rec.2020'") &&
                          Catch::Contains("'sRGB'") && Catch::Contains("'XYZ'"));
    settings = DisplaySettings{};
    settings.look = "Punchy";
    CHECK_THROWS_WITH(write_png(path, 1, 1, rgb.data(), settings),
                      Catch::Contains("unknown look 'Punchy'") &&
                          Catch::Contains("'High Contrast'"));
    settings = DisplaySettings{};
    settings.config_path = dir / "missing.ocio";
    CHECK_THROWS_AS(write_png(path, 1, 1, rgb.data(), settings), std::runtime_error);
    CHECK(dir.entries().empty());
}

TEST_CASE("Writers refuse a destination whose directory does not exist", "[io]") {
    TempDir dir;
    const std::string path = dir / "missing/sub/bake.exr";
    ImageChannels img{1, 1, {"R"}, {1.0f}};
    CHECK_THROWS_AS(write_exr(path, img), std::runtime_error);
    CHECK_THROWS_WITH(write_exr(path, img), Catch::Contains(path) &&
                                                Catch::Contains("does not exist"));
    const std::vector<float> rgb(3, 0.5f);
    CHECK_THROWS_WITH(write_png(dir / "missing/x.png", 1, 1, rgb.data(), {}),
                      Catch::Contains("does not exist"));
    write_bytes(dir / "file", "x");
    CHECK_THROWS_WITH(write_exr(dir / "file/bake.exr", img),
                      Catch::Contains("is not a directory"));
    CHECK(dir.entries() == std::vector<std::string>{"file"});
}

TEST_CASE("Writers replace atomically and clean up after failures", "[io]") {
    TempDir dir;
    const std::string path = dir / "bake.exr";
    const std::string png_path = dir / "bake.png";
    const std::string old_exr = "previous EXR bytes\n";
    const std::string old_png = "previous PNG bytes\n";
    write_bytes(path, old_exr);
    write_bytes(png_path, old_png);
    ::chmod(path.c_str(), 0640);
    const std::vector<std::string> both{"bake.exr", "bake.png"};

    SECTION("a successful write replaces the file and keeps its permissions") {
        write_exr(path, ImageChannels{1, 1, {"R"}, {0.25f}});
        CHECK(read_bytes(path) != old_exr);
        struct stat st;
        REQUIRE(::stat(path.c_str(), &st) == 0);
        CHECK((st.st_mode & 07777) == 0640);
        CHECK(dir.entries() == both);
    }
    SECTION("a destination that is a directory") {
        fs::create_directory(dir / "taken.exr");
        CHECK_THROWS_AS(write_exr(dir / "taken.exr", ImageChannels{1, 1, {"R"}, {1.0f}}),
                        std::runtime_error);
        CHECK(fs::is_directory(dir / "taken.exr"));
        CHECK(fs::is_empty(dir / "taken.exr"));
        CHECK(dir.entries() == std::vector<std::string>{"bake.exr", "bake.png", "taken.exr"});
    }
    SECTION("the disk fills up in the middle of the EXR") {
        // 128x128x5 incompressible floats are ~320 KB; the limit stops at 64 KB,
        // after OpenImageIO has created the temporary file and begun writing.
        const ImageChannels img = noise_image(128, 128, {"R", "G", "B", "noise", "mask"});
        {
            FileSizeLimit limit(64 * 1024);
            CHECK_THROWS_WITH(write_exr(path, img),
                              Catch::Contains(path) && Catch::Contains("File too large"));
        }
        CHECK(read_bytes(path) == old_exr);
        CHECK(dir.entries() == both);
        write_exr(path, img);  // and works again without the limit
        CHECK(dir.entries() == both);
    }
    SECTION("the disk fills up in the middle of the PNG") {
        const ImageChannels img = noise_image(256, 256, {"R", "G", "B"});
        {
            FileSizeLimit limit(16 * 1024);
            CHECK_THROWS_WITH(write_png(png_path, 256, 256, img.pixels.data(), {}),
                              Catch::Contains(png_path) &&
                                  Catch::Contains("File too large"));
        }
        CHECK(read_bytes(png_path) == old_png);
        CHECK(dir.entries() == both);
    }
}
