// A texture's decoded image as lookups read it: an 8-bit file (PNG, JPEG, ...) keeps its bytes,
// three a texel, and reads them as floats 0..255, the values the course's formulas take; a .hdr
// or .exr file keeps its floats (an Image). Both read the same numbers, so a lookup gives the same
// bits from either.
// Why not floats for all: the course's photographs are 1-6 million texels, which as floats were
// 12 bytes each (72 MB for hw4 VeachAjar's largest), four times the bytes' memory, and writing
// them was most of a textured scene's loading: converting and touching the fresh pages took 12%
// of hw7 VeachAjar's whole run at --scale 0.25 on the 2-vCPU VM (perf), where the first write to
// a fresh page costs far more than on bare metal. The decoder keeps the bytes in huge pages
// (image_io.hpp, decode_texels), as the floats were: lookups land anywhere in a photograph.
#pragma once

#include <prism/image/image.hpp>

#include <glm/glm.hpp>

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>

namespace prism {

class Texels {
public:
    // The bytes of an 8-bit image, red, green and blue a texel, row by row from the top left;
    // `rgb` owns them (or shares their owner: the decoder's huge-page array).
    struct Bytes {
        int width = 0;
        int height = 0;
        std::shared_ptr<const std::uint8_t> rgb;
        glm::vec3 operator()(int x, int y) const {
            assert(x >= 0 && x < width && y >= 0 && y < height);
            const std::uint8_t* texel = rgb.get() + 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
            return glm::vec3(float(texel[0]), float(texel[1]), float(texel[2]));
        }
    };

    explicit Texels(std::shared_ptr<const Image> radiance) : floats_(std::move(radiance)) {}
    explicit Texels(Image radiance) : floats_(std::make_shared<const Image>(std::move(radiance))) {}
    explicit Texels(Bytes bytes) : bytes_(std::move(bytes)) {}

    int width() const { return floats_ ? floats_->width : bytes_.width; }
    int height() const { return floats_ ? floats_->height : bytes_.height; }
    bool empty() const { return width() <= 0 || height() <= 0 || (floats_ ? floats_->pixels.empty() : !bytes_.rgb); }

    // Texel (x, y) as floats.
    glm::vec3 operator()(int x, int y) const { return floats_ ? (*floats_)(x, y) : bytes_(x, y); }

    // `read(image)` with the image's own storage (an Image or Bytes, both read by (x, y) and
    // giving glm::vec3): one choice a lookup, not one a texel.
    template <class Read>
    decltype(auto) visit(Read&& read) const {
        return floats_ ? read(*floats_) : read(bytes_);
    }

    // The floats, shared where the texels are floats already; a copy of the bytes otherwise (an
    // environment map decoded from an 8-bit file).
    std::shared_ptr<const Image> radiance() const {
        if (floats_) return floats_;
        auto image = std::make_shared<Image>(bytes_.width, bytes_.height, Image::Unfilled{});
        for (int y = 0; y < bytes_.height; ++y)
            for (int x = 0; x < bytes_.width; ++x) (*image)(x, y) = bytes_(x, y);
        return image;
    }

    // Whether the texels are kept as bytes (an 8-bit file's).
    bool bytes() const { return !floats_; }
    std::size_t memory_bytes() const {
        return floats_ ? floats_->pixels.size() * sizeof(glm::vec3)
                       : 3 * std::size_t(bytes_.width) * std::size_t(bytes_.height);
    }

private:
    std::shared_ptr<const Image> floats_;  // set for floats
    Bytes bytes_;                          // otherwise
};

}  // namespace prism
