// The HDR film: linear radiance in single-precision floating point, row-major from the top-left
// pixel. Whatever precision the renderer traced in, images are kept in float to the end.
#pragma once

#include <prism/memory/huge_page_allocator.hpp>

#include <glm/glm.hpp>

#include <cassert>
#include <cstddef>
#include <vector>

namespace prism {

// The film's storage: huge pages, and no clearing of a film the renderer fills whole
// (Image::Unfilled); see memory/huge_page_allocator.hpp.
template <class T>
using FilmAllocator = HugePageAllocator<T>;

struct Image {
    int width = 0;
    int height = 0;
    std::vector<glm::vec3, FilmAllocator<glm::vec3>> pixels;

    // A film whose pixels the caller writes, every one, before reading any (the renderer's).
    struct Unfilled {};

    Image() = default;
    Image(int width_, int height_)
        : width(width_), height(height_),
          pixels(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), glm::vec3(0.0f)) {}
    Image(int width_, int height_, Unfilled)
        : width(width_), height(height_), pixels(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_)) {}

    glm::vec3& operator()(int x, int y) {
        assert(x >= 0 && x < width && y >= 0 && y < height);
        return pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
    }
    const glm::vec3& operator()(int x, int y) const {
        assert(x >= 0 && x < width && y >= 0 && y < height);
        return pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
    }
};

// Repeat addressing (a texture's or a lat-long map's wrap): `index` wrapped into [0, size), by
// the remainder's one integer division. No branch around the division for an index already
// inside: with (u, v) beyond [0, 1) half the time (tiled textures), its mispredictions took
// nearest lookups to 1.6-2.3 times as long (prism_texture_bench).
inline int repeat_index(int index, int size) {
    const int wrapped = index % size;
    return wrapped < 0 ? wrapped + size : wrapped;
}
// The repeated index after `index`, which is in [0, size): repeat_index(index + 1, size) without
// a second division (a bilinear lookup's other column and row).
inline int repeat_next(int index, int size) { return index + 1 == size ? 0 : index + 1; }

// Pixels per run of the passes over an image that run on TBB's threads (decode_image's
// conversion): 3 MB of film, about a huge page and a half, so that two threads seldom fault in
// the same page.
inline constexpr std::size_t image_pass_grain = std::size_t(1) << 18;

}  // namespace prism
