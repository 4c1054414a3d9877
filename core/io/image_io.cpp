#include "io/image_io.h"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <fcntl.h>
#include <glob.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef OMIS_IO_VERSION_STRING
#define OMIS_IO_VERSION_STRING "unknown"
#endif

namespace OCIO = OCIO_NAMESPACE;

namespace omis {
namespace {

std::string quoted(const std::string& s) { return "'" + s + "'"; }

std::string join(const std::vector<std::string>& items) {
    std::string out;
    for (const std::string& item : items) {
        if (!out.empty()) out += ", ";
        out += quoted(item);
    }
    return out;
}

[[noreturn]] void fail(const char* writer, const std::string& path,
                       const std::string& why) {
    throw std::runtime_error(std::string(writer) + ": cannot write " + quoted(path) +
                             ": " + why);
}

// The process umask, without the race of setting and restoring it.
mode_t current_umask() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("Umask:", 0) == 0) {
            return static_cast<mode_t>(std::strtoul(line.c_str() + 6, nullptr, 8));
        }
    }
    return 022;
}

// A temporary file beside the destination (same directory, hence same file
// system, so rename() replaces the destination atomically). Removed by the
// destructor unless commit() moved it into place.
class TempFile {
public:
    TempFile(const char* writer, const std::string& path) : writer_(writer), path_(path) {
        const std::size_t slash = path.rfind('/');
        dir_ = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
        std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
        if (base.empty() || base == "." || base == "..") {
            fail(writer, path, "the path names a directory, not a file");
        }

        struct stat st;
        if (::stat(dir_.c_str(), &st) != 0) {
            fail(writer, path,
                 errno == ENOENT ? "directory " + quoted(dir_) + " does not exist"
                                 : "cannot access directory " + quoted(dir_) + ": " +
                                       std::strerror(errno));
        }
        if (!S_ISDIR(st.st_mode)) fail(writer, path, quoted(dir_) + " is not a directory");

        // A replaced file keeps its permissions; a new one gets the usual ones.
        mode_t mode = 0666 & ~current_umask();
        if (::stat(path.c_str(), &st) == 0) {
            if (S_ISDIR(st.st_mode)) fail(writer, path, "it is an existing directory");
            if (S_ISREG(st.st_mode)) mode = st.st_mode & 07777;
        }

        // Keep the name within NAME_MAX whatever the destination's length.
        if (base.size() > 200) base.resize(200);
        const std::string prefix = slash == std::string::npos ? "" : path.substr(0, slash + 1);
        std::string name = prefix + "." + base + ".omis-XXXXXX.tmp";
        std::vector<char> templ(name.begin(), name.end());
        templ.push_back('\0');
        fd_ = ::mkostemps(templ.data(), 4, O_CLOEXEC);
        if (fd_ < 0) {
            fail(writer, path, "cannot create a temporary file in " + quoted(dir_) + ": " +
                                   std::strerror(errno));
        }
        tmp_ = templ.data();
        if (::fchmod(fd_, mode) != 0) {
            const int e = errno;
            ::close(fd_);  // no destructor runs for a throwing constructor
            ::unlink(tmp_.c_str());
            fail(writer, path, "cannot set permissions of the temporary file: " +
                                   std::string(std::strerror(e)));
        }
    }

    ~TempFile() {
        if (fd_ >= 0) ::close(fd_);
        if (!committed_) ::unlink(tmp_.c_str());
    }
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;

    const std::string& path() const { return tmp_; }
    int fd() const { return fd_; }

    // Flush the complete file to disk, then rename it over the destination, so
    // that after a crash the destination is either the old or the new file.
    void commit() {
        if (::fsync(fd_) != 0) {
            fail(writer_, path_, "cannot flush the temporary file " + quoted(tmp_) + ": " +
                                     std::strerror(errno));
        }
        const int fd = fd_;
        fd_ = -1;
        if (::close(fd) != 0) {
            fail(writer_, path_, "cannot close the temporary file " + quoted(tmp_) + ": " +
                                     std::strerror(errno));
        }
        if (::rename(tmp_.c_str(), path_.c_str()) != 0) {
            fail(writer_, path_, "cannot rename the temporary file " + quoted(tmp_) +
                                     " over it: " + std::strerror(errno));
        }
        committed_ = true;
        // Make the rename itself durable; the file is in place either way.
        const int dir_fd = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
        if (dir_fd >= 0) {
            ::fsync(dir_fd);
            ::close(dir_fd);
        }
    }

private:
    const char* writer_;
    std::string path_;
    std::string dir_;
    std::string tmp_;
    int fd_ = -1;
    bool committed_ = false;
};

// OpenImageIO's output through a file descriptor, checking every write: some
// of its writers (PNG in 2.4) ignore failed writes and report success, which
// would rename a truncated file into place.
class CheckedFdOutput : public OIIO::Filesystem::IOProxy {
public:
    CheckedFdOutput(const std::string& name, int fd) : IOProxy(name, Write), fd_(fd) {}
    const char* proxytype() const override { return "omis-fd"; }
    bool seek(int64_t offset) override {
        if (offset < 0) return false;
        m_pos = offset;
        return true;
    }
    size_t write(const void* buf, size_t size) override {
        const size_t done = pwrite(buf, size, m_pos);
        m_pos += int64_t(done);
        return done;
    }
    size_t pwrite(const void* buf, size_t size, int64_t offset) override {
        const char* p = static_cast<const char*>(buf);
        size_t done = 0;
        while (done < size) {
            const ssize_t n = ::pwrite(fd_, p + done, size - done, offset + int64_t(done));
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                if (first_errno_ == 0) first_errno_ = n < 0 ? errno : EIO;
                break;
            }
            done += size_t(n);
        }
        size_ = std::max(size_, size_t(offset) + done);
        return done;
    }
    size_t size() const override { return size_; }
    // The first failed write's errno, 0 if none failed.
    int first_errno() const { return first_errno_; }

private:
    int fd_;
    size_t size_ = 0;
    int first_errno_ = 0;
};

// Writes `pixels` (bottom row first, rows of `row_bytes`) as a top-row-first
// file of `format` atomically at `path`.
void write_atomically(const char* writer, const std::string& path, const char* format,
                      const OIIO::ImageSpec& spec, OIIO::TypeDesc type,
                      const unsigned char* pixels, std::ptrdiff_t row_bytes) {
    TempFile tmp(writer, path);
    CheckedFdOutput proxy(tmp.path(), tmp.fd());
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(format);
    if (!out) fail(writer, path, "OpenImageIO: " + OIIO::geterror());
    if (!out->set_ioproxy(&proxy)) fail(writer, path, "OpenImageIO: " + out->geterror());
    // The first failed write explains whatever the writer made of it.
    auto oiio_failure = [&](const std::string& error) {
        std::string why = "OpenImageIO: " + error;
        if (proxy.first_errno() != 0) {
            why = std::string(std::strerror(proxy.first_errno())) + " (" + why + ")";
        }
        fail(writer, path, why);
    };
    if (!out->open(tmp.path(), spec)) oiio_failure(out->geterror());
    // Start at the last buffer row with a negative row stride: the file's first
    // scanline is the image's top row.
    const unsigned char* top = pixels + (spec.height - 1) * row_bytes;
    if (!out->write_image(type, top, OIIO::AutoStride, -row_bytes)) {
        const std::string error = out->geterror();
        out->close();
        oiio_failure(error);
    }
    if (!out->close()) oiio_failure(out->geterror());
    out.reset();
    if (proxy.first_errno() != 0) {
        fail(writer, path, std::string(std::strerror(proxy.first_errno())) +
                               " while writing the temporary file " + quoted(tmp.path()));
    }
    tmp.commit();
}

void check_size(const char* writer, int width, int height) {
    if (width <= 0 || height <= 0) {
        throw std::invalid_argument(std::string(writer) + ": image size " +
                                    std::to_string(width) + "x" + std::to_string(height) +
                                    " is not positive");
    }
}

// ---- Display transform --------------------------------------------------------

std::string resolve_config_path(const DisplaySettings& settings) {
    if (!settings.config_path.empty()) return settings.config_path;
    std::string path = find_blender_ocio_config();
    if (path.empty()) {
        if (const char* env = std::getenv("OCIO"); env && *env) path = env;
    }
    return path;
}

bool is_no_look(const std::string& look) { return look.empty() || look == "None"; }

float srgb_oetf(float v) {
    if (!(v > 0.0f)) return 0.0f;  // also NaN
    if (v <= 0.0031308f) return 12.92f * v;
    return 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

// The processor Blender builds for its image editor and for saving "as render"
// (intern/opencolorio/ocio_impl.cc, createDisplayProcessor): exposure as a
// scale in scene linear, then the look, then the display/view transform.
OCIO::ConstCPUProcessorRcPtr display_processor(const OCIO::ConstConfigRcPtr& config,
                                               const DisplaySettings& settings) {
    std::vector<std::string> displays;
    for (int i = 0; i < config->getNumDisplays(); ++i) displays.push_back(config->getDisplay(i));
    if (std::find(displays.begin(), displays.end(), settings.display) == displays.end()) {
        throw std::invalid_argument("write_png: unknown display " + quoted(settings.display) +
                                    "; available displays: " + join(displays));
    }
    std::vector<std::string> views;
    const char* display = settings.display.c_str();
    for (int i = 0; i < config->getNumViews(display); ++i) {
        views.push_back(config->getView(display, i));
    }
    if (std::find(views.begin(), views.end(), settings.view) == views.end()) {
        throw std::invalid_argument("write_png: unknown view " + quoted(settings.view) +
                                    " for display " + quoted(settings.display) +
                                    "; available views: " + join(views));
    }
    const bool want_look = !is_no_look(settings.look);
    if (want_look && !config->getLook(settings.look.c_str())) {
        std::vector<std::string> looks{"None"};
        for (int i = 0; i < config->getNumLooks(); ++i) {
            looks.push_back(config->getLookNameByIndex(i));
        }
        throw std::invalid_argument("write_png: unknown look " + quoted(settings.look) +
                                    "; available looks: " + join(looks));
    }

    OCIO::GroupTransformRcPtr group = OCIO::GroupTransform::Create();
    std::string input = OCIO::ROLE_SCENE_LINEAR;
    if (settings.exposure != 0) {
        const double s = std::exp2(settings.exposure);
        const double m[16] = {s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0, 0, 0, 0, 1};
        OCIO::MatrixTransformRcPtr scale = OCIO::MatrixTransform::Create();
        scale->setMatrix(m);
        group->appendTransform(scale);
    }
    bool use_look = false;
    if (want_look) {
        const char* look_output = OCIO::LookTransform::GetLooksResultColorSpace(
            config, config->getCurrentContext(), settings.look.c_str());
        if (look_output && *look_output) {  // an empty look has no output space
            OCIO::LookTransformRcPtr look = OCIO::LookTransform::Create();
            look->setSrc(input.c_str());
            look->setDst(look_output);
            look->setLooks(settings.look.c_str());
            group->appendTransform(look);
            input = look_output;
            use_look = true;
        }
    }
    OCIO::DisplayViewTransformRcPtr dvt = OCIO::DisplayViewTransform::Create();
    dvt->setSrc(input.c_str());
    dvt->setLooksBypass(use_look);
    dvt->setDisplay(settings.display.c_str());
    dvt->setView(settings.view.c_str());
    group->appendTransform(dvt);
    return config->getProcessor(group)->getDefaultCPUProcessor();
}

// Turns linear RGB into display-encoded RGB in place.
void apply_display(const DisplaySettings& settings, int width, int height,
                   std::vector<float>& rgb) {
    const std::string config_path = resolve_config_path(settings);
    if (config_path.empty()) {
        if (settings.view != "Standard" || settings.display != "sRGB" ||
            !is_no_look(settings.look)) {
            throw std::invalid_argument(
                "write_png: no OCIO config found (no Blender config, $OCIO unset), so "
                "only view 'Standard' on display 'sRGB' without a look is available; "
                "asked for view " + quoted(settings.view) + " on display " +
                quoted(settings.display) + " with look " + quoted(settings.look));
        }
        const float scale = static_cast<float>(std::exp2(settings.exposure));
        for (float& v : rgb) v = srgb_oetf(v * scale);
        return;
    }

    OCIO::ConstConfigRcPtr config;
    try {
        config = OCIO::Config::CreateFromFile(config_path.c_str());
    } catch (const OCIO::Exception& e) {
        throw std::runtime_error("write_png: cannot load the OCIO config " +
                                 quoted(config_path) + ": " + e.what());
    }
    OCIO::ConstCPUProcessorRcPtr cpu;
    try {
        cpu = display_processor(config, settings);
    } catch (const OCIO::Exception& e) {
        throw std::runtime_error("write_png: OCIO config " + quoted(config_path) +
                                 " cannot build view " + quoted(settings.view) +
                                 " on display " + quoted(settings.display) + ": " +
                                 e.what());
    }
    OCIO::PackedImageDesc desc(rgb.data(), width, height, 3);
    cpu->apply(desc);
}

// Blender's unit_float_to_uchar_clamp: round to nearest, clamp, NaN to 0.
unsigned char to_byte(float v) {
    if (!(v > 0.0f)) return 0;
    if (v > 1.0f - 0.5f / 255.0f) return 255;
    return static_cast<unsigned char>(255.0f * v + 0.5f);
}

// The file system stops a name at a NUL byte: 'a\0.exr' would silently
// write 'a'.
void check_path(const char* writer, const std::string& path) {
    if (path.find('\0') != std::string::npos)
        throw std::invalid_argument(std::string(writer) + ": path " +
                                    quoted(path.substr(0, path.find('\0'))) +
                                    "... contains a NUL byte");
}

}  // namespace

void write_exr(const std::string& path, const ImageChannels& image) {
    check_path("write_exr", path);
    check_size("write_exr", image.width, image.height);
    const std::size_t channels = image.names.size();
    if (channels == 0) throw std::invalid_argument("write_exr: no channel names");
    std::set<std::string> unique;
    for (const std::string& name : image.names) {
        if (name.empty()) throw std::invalid_argument("write_exr: empty channel name");
        if (!unique.insert(name).second) {
            throw std::invalid_argument("write_exr: channel name " + quoted(name) +
                                        " appears twice");
        }
    }
    const std::size_t expected =
        std::size_t(image.width) * std::size_t(image.height) * channels;
    if (image.pixels.size() != expected) {
        throw std::invalid_argument(
            "write_exr: " + std::to_string(image.width) + "x" +
            std::to_string(image.height) + " pixels of " + std::to_string(channels) +
            " channels need " + std::to_string(expected) + " floats, got " +
            std::to_string(image.pixels.size()));
    }

    OIIO::ImageSpec spec(image.width, image.height, int(channels), OIIO::TypeDesc::FLOAT);
    spec.channelnames = image.names;
    spec.alpha_channel = -1;  // "A" among the names is data like any other here
    spec.attribute("compression", "zip");
    spec.attribute("Software", "omis " OMIS_IO_VERSION_STRING);
    write_atomically("write_exr", path, "openexr", spec, OIIO::TypeDesc::FLOAT,
                     reinterpret_cast<const unsigned char*>(image.pixels.data()),
                     std::ptrdiff_t(image.width * channels * sizeof(float)));
}

void write_png(const std::string& path, int width, int height, const float* rgb,
               const DisplaySettings& display) {
    check_path("write_png", path);
    check_size("write_png", width, height);
    if (!std::isfinite(display.exposure))
        throw std::invalid_argument("write_png: exposure must be a finite number of stops");
    if (!rgb) throw std::invalid_argument("write_png: rgb is null");
    const std::size_t values = std::size_t(width) * std::size_t(height) * 3;
    std::vector<float> encoded(rgb, rgb + values);
    apply_display(display, width, height, encoded);  // throws before any file is made
    std::vector<unsigned char> bytes(values);
    std::transform(encoded.begin(), encoded.end(), bytes.begin(), to_byte);

    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("Software", "omis " OMIS_IO_VERSION_STRING);
    write_atomically("write_png", path, "png", spec, OIIO::TypeDesc::UINT8, bytes.data(),
                     std::ptrdiff_t(width) * 3);
}

std::string find_blender_ocio_config() {
    const std::string tail = "/datafiles/colormanagement/config.ocio";
    std::vector<std::string> candidates;
    if (const char* env = std::getenv("BLENDER_SYSTEM_DATAFILES"); env && *env) {
        candidates.push_back(std::string(env) + "/colormanagement/config.ocio");
    }
    // Debian's package installs without a version folder; Blender's own
    // tarballs and older packages use <root>/<major.minor>/datafiles.
    for (const char* root : {"/usr/share/blender", "/usr/local/share/blender"}) {
        candidates.push_back(root + tail);
        const std::string pattern = std::string(root) + "/*" + tail;
        glob_t found;
        if (::glob(pattern.c_str(), 0, nullptr, &found) == 0) {
            std::vector<std::string> paths(found.gl_pathv, found.gl_pathv + found.gl_pathc);
            std::sort(paths.begin(), paths.end(), [](const std::string& a, const std::string& b) {
                return ::strverscmp(a.c_str(), b.c_str()) > 0;  // newest first
            });
            candidates.insert(candidates.end(), paths.begin(), paths.end());
        }
        ::globfree(&found);
    }
    for (const std::string& path : candidates) {
        struct stat st;
        if (::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
            ::access(path.c_str(), R_OK) == 0) {
            return path;
        }
    }
    return "";
}

}  // namespace omis
