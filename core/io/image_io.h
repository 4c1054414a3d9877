// Writing bake results to image files. Both writers are atomic: the image goes
// to a temporary file beside the destination and is renamed over it only once
// complete, so a reader (Blender reloading the image, a compositor watching the
// folder) never sees a half-written file and a failed write leaves the old one.
#pragma once

#include <string>
#include <vector>

namespace omis {

// Interleaved float channels; row 0 is the BOTTOM row, as Blender stores image
// pixels and as the baker produces them. Writers flip to top-first for files.
struct ImageChannels {
    int width = 0;
    int height = 0;
    std::vector<std::string> names;  // one per channel, e.g. "R","G","B","noise"
    std::vector<float> pixels;       // width * height * names.size() values
};

// How linear scene-referred values are turned into display values, as in
// Blender's Color Management panel (view transform, display device, look,
// exposure in stops applied in scene linear before the view).
struct DisplaySettings {
    std::string view = "Standard";
    std::string display = "sRGB";
    std::string look = "None";  // "None" or "" = no look
    double exposure = 0;
    // OCIO config file; empty = Blender's config if found, else $OCIO, else a
    // plain sRGB OETF (which knows only view "Standard" on display "sRGB").
    std::string config_path;
};

// 32-bit float OpenEXR, ZIP compressed, channels named as given. Throws
// std::invalid_argument for an inconsistent image and std::runtime_error naming
// the path for any I/O failure (the destination is then left untouched).
void write_exr(const std::string& path, const ImageChannels& image);

// 8-bit RGB PNG of linear scene-referred `rgb` (width * height * 3 floats,
// bottom row first) through the OCIO display/view transform of `display`, so it
// looks as it does in Blender's image editor with the same settings. Throws
// std::invalid_argument for an unknown view, display or look (listing the
// available ones) and std::runtime_error as write_exr does.
void write_png(const std::string& path, int width, int height, const float* rgb,
               const DisplaySettings& display = {});

// Blender's OCIO config on this machine ($BLENDER_SYSTEM_DATAFILES, then the
// Debian and tarball locations, newest version first); "" if none is found.
std::string find_blender_ocio_config();

}  // namespace omis
