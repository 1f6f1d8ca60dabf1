// The limits that keep a hostile or mistaken scene file from exhausting memory or the native stack.
// Each is chosen from what the course's scenes use (../shared/ceng795, hw1-hw7: MaxRecursionDepth
// at most 6, NumSamples at most 2500, images at most 1920 x 1080 rendered and 2000 x 3008 read),
// with an order of magnitude of headroom. A file past a limit is refused with a LoadError naming
// the element, before anything is allocated for it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <unistd.h>

namespace prism::io {

// Nested elements deeper than this are refused: the course's files nest 4 deep (Scene, Objects,
// Mesh, Faces), and the element tree is built, labelled and destroyed by recursion, so its depth
// must not be the input's to choose.
inline constexpr int max_element_depth = 64;

// The Whitted integrator recurses once per reflection or refraction on the native stack (of a TBB
// worker: 4 MiB on 64-bit). stack_safe_recursion_depth is the most --max-recursion-depth may allow.
// Measured on hw2's mirror_room (two facing mirrors, so rays do bounce that deep), Release build,
// --threads 1 under `ulimit -s`: 512 levels run in 1 MiB of stack, float and double alike; 1024
// levels need more than 1 MiB and less than 2.
inline constexpr int stack_safe_recursion_depth = 512;

// Rendered images: either side at most 32768 pixels and at most 2^27 pixels in all (134 million;
// its film of float RGB takes 1.5 GiB). Read images (textures, environment maps) likewise.
inline constexpr std::int64_t max_image_side = 32768;
inline constexpr std::int64_t max_image_pixels = std::int64_t(1) << 27;

// Files a scene names (and the scene file itself) are read whole, so their size is bounded before
// they are read: a sparse file of any size costs nothing on disk, and one of 3 GB named as a
// texture was read into 3 GB of memory before its content was refused. The course's largest
// file is 3.9 MB (an EXR); stb_image reads at most 2 GiB; a binary PLY of 2 GiB holds some 60
// million triangles, which take more than 17 GB to render.
inline constexpr std::uint64_t max_file_bytes = std::uint64_t(1) << 31;

// A scene file's text is held three times while it is read (the file's bytes, pugixml's copy,
// each element's text) and its numbers twice more (parsed, then made vertices): 256 MiB of
// inline VertexData takes 2.3 GiB (bench/RESULTS.md, "Reading scene files"). The course's
// largest scene file is 2.1 MB (a JSON file with its meshes inline); meshes beyond a few million
// triangles belong in PLY or binary files, which are read without the element tree.
inline constexpr std::uint64_t max_scene_file_bytes = std::uint64_t(1) << 28;

// Elements and attributes in a scene file: each costs 160-230 bytes of memory as it is read
// (pugixml's node, the element tree's Element, its path), 40-60 times the few bytes it takes in
// the file: 16 million empty elements (`<a/>`, 64 MB) took 3.6 GiB, and a file of the 2 GiB a
// file may hold would have taken some 120 GB. They are counted before pugixml builds its tree
// (XML) and as the tree is built (JSON). The course's files hold at most 673 (tower.xml).
inline constexpr std::uint64_t max_scene_nodes = std::uint64_t(1) << 22;

// A Perlin texture's NumOctaves: each octave is one more noise evaluation a lookup (a file asking
// for 2^31 - 1 of them had not rendered 16 x 16 pixels after 30 s), and past 53 an octave's
// weight, 2^-53 of the first's, is below what a double holds of their sum. The course's files
// give none (1).
inline constexpr long long max_noise_octaves = 64;

// Textures an object's <Textures> list names: each is applied at every shading point of the
// object, so the list's length multiplies the render's time (100,000 entries naming one Perlin
// texture took a 200 x 200 render from 0.01 s to 9.9 s). The course's lists name at most 2.
inline constexpr std::size_t max_textures_per_object = 64;

// Samples per pixel: the course's most is 2500.
inline constexpr std::int64_t max_samples_per_pixel = 65536;

// Memory a triangle costs from loading to rendering: the peak resident size of `prism` on a flat
// grid mesh from a binary PLY (2 and 8 million triangles, half as many vertices, 16 x 16 pixels)
// grew by 160 bytes a triangle with --precision float and 268 with double; rounded up.
inline constexpr std::uint64_t render_bytes_per_triangle = 300;

// Memory a texture image's texel costs beyond its stored bytes (image_extent's texel_bytes): its
// MIP levels add a third. An 8-bit image of 2^26 texels raised the peak resident size of `prism`
// by 3.7 bytes a texel (8 such images, a 16 x 16 render).
inline constexpr std::uint64_t texture_bytes(std::uint64_t texels, std::uint64_t texel_bytes) {
    return texels * texel_bytes * 4 / 3;
}

// The machine's physical memory (0 when the system will not say).
inline std::uint64_t physical_memory_bytes() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page_size = ::sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page_size > 0 ? std::uint64_t(pages) * std::uint64_t(page_size) : 0;
}

// The limits that may differ from one run to the next; the others are fixed.
struct ResourceLimits {
    // The course's scenes ask for at most 6; 64 leaves ten times that. prism
    // --max-recursion-depth sets it, up to stack_safe_recursion_depth. Each Whitted dielectric
    // bounce traces two rays, so time, not stack, is what a deep glass scene runs out of first.
    int max_recursion_depth = 64;
    // A scene whose meshes would need more than this to render (render_bytes_per_triangle each)
    // is refused at the mesh that passes it, instead of failing later in an allocation.
    std::uint64_t memory_bytes = physical_memory_bytes();
};

// A camera's film: float RGB a pixel, every camera's kept until all are rendered (so that a
// scene that fails writes no image).
inline constexpr std::uint64_t film_bytes_per_pixel = 12;

// What the meshes, texture images and films a loader has read so far will take to render, which
// together may not pass ResourceLimits::memory_bytes. Each alone has its limit (the image and
// resolution limits above), and many of them still passed the machine's memory: a scene of many
// large images (a few hundred kB of PNG for 2^26 texels of one colour) was decoded until the
// memory ran out, and one of many 2^27-pixel cameras rendered until it did.
struct MemoryUse {
    std::uint64_t triangles = 0;
    std::uint64_t texture_bytes = 0;
    std::uint64_t film_bytes = 0;
    std::uint64_t bytes() const { return triangles * render_bytes_per_triangle + texture_bytes + film_bytes; }
    bool over(std::uint64_t limit) const { return limit != 0 && bytes() > limit; }
    // What a scene that passes `limit` is told, after what its element added.
    std::string over_message(std::uint64_t limit) const {
        return "about " + mib(bytes()) + " to render (meshes " + mib(triangles * render_bytes_per_triangle) +
               ", textures " + mib(texture_bytes) + ", films " + mib(film_bytes) + "), more than the " + mib(limit) +
               " of memory prism may use";
    }
    static std::string mib(std::uint64_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }
};

}  // namespace prism::io
