#include "io/image_read.h"

#include <OpenImageIO/imageio.h>

#include <memory>
#include <stdexcept>

namespace omis {

RgbImage read_rgb_image(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        throw std::runtime_error("world image: cannot open '" + path +
                                 "': " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    const int channels = spec.nchannels;
    if (channels < 1 || spec.width < 1 || spec.height < 1 || spec.depth > 1)
        throw std::runtime_error("world image: '" + path +
                                 "' is not a 2-D image with channels");
    std::vector<float> all(std::size_t(spec.width) * spec.height * channels);
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, all.data()))
        throw std::runtime_error("world image: cannot read '" + path +
                                 "': " + in->geterror());
    in->close();
    RgbImage image;
    image.width = spec.width;
    image.height = spec.height;
    image.rgb.resize(std::size_t(spec.width) * spec.height * 3);
    // Fewer than three channels: grey (with alpha when two).
    const bool grey = channels < 3;
    for (std::size_t p = 0, n = std::size_t(spec.width) * spec.height; p < n; ++p)
        for (int c = 0; c < 3; ++c)
            image.rgb[3 * p + c] = all[p * channels + (grey ? 0 : c)];
    return image;
}

}  // namespace omis
