// Reading an RGB radiance image (an HDRI for the world) with OpenImageIO.
#pragma once

#include <string>
#include <vector>

namespace omis {

// Linear float RGB, rows TOP first (as the file stores them and as
// EnvironmentMap takes them). Grey images are spread to RGB; a fourth and
// further channels (alpha) are dropped.
struct RgbImage {
    int width = 0, height = 0;
    std::vector<float> rgb;  // width * height * 3
};

// Any format OpenImageIO reads (EXR, Radiance HDR, ...). Throws
// std::runtime_error naming the path when it cannot be opened or read.
RgbImage read_rgb_image(const std::string& path);

}  // namespace omis
