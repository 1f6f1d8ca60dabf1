// Image files: the course's 8-bit conversion, writing PNG, PPM and EXR (prism's own encoders,
// png_encoder.hpp and exr_encoder.hpp), reading PNG/JPG/BMP/TGA/PPM, Radiance .hdr and OpenEXR
// (scanline or tiled) into the HDR film. stb and tinyexr, the readers, are compiled in their
// system libraries (libstb, libtinyexr), so no *_IMPLEMENTATION macro is defined here.
#pragma once

#include <prism/image/decoder_guard.hpp>
#include <prism/image/exr_encoder.hpp>
#include <prism/image/image.hpp>
#include <prism/image/png_encoder.hpp>
#include <prism/image/texels.hpp>
#include <prism/io/limits.hpp>
#include <prism/io/load_error.hpp>
#include <prism/io/read_file.hpp>
#include <prism/parallel/for_each_run.hpp>

#include <stb_image.h>
#include <stb_image_write.h>
#include <tinyexr.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

#include <unistd.h>

namespace prism {

// The course's LDR conversion of every channel (channel_to_8bit): interleaved RGB, row-major
// from the top-left pixel.
inline std::vector<std::uint8_t> to_8bit(const Image& image) {
    std::vector<std::uint8_t> bytes(image.pixels.size() * 3);
    std::size_t i = 0;
    for (const glm::vec3& pixel : image.pixels)
        for (int c = 0; c < 3; ++c) bytes[i++] = channel_to_8bit(pixel[c]);
    return bytes;
}

namespace detail {

inline std::string lowercase_extension(const std::filesystem::path& path) {
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return extension;
}

// A temporary name next to the final file, so that the rename that publishes it stays on one
// file system (and is therefore atomic). Process id and a counter keep concurrent writers apart.
inline std::filesystem::path temporary_sibling(const std::filesystem::path& path) {
    static std::atomic<unsigned> counter{0};
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict, GCC bug 105651) on a literal
    // prepended to a temporary string where it inlines the insertion.
    std::string suffix = ".";
    suffix += std::to_string(::getpid());
    suffix += '.';
    suffix += std::to_string(counter++);
    suffix += ".tmp";
    // The name is cut from its start where the whole would pass a file name's NAME_MAX bytes: an
    // image name of 250 bytes is allowed (io::confined_output_path), and its temporary file
    // must be too.
    std::string name = path.filename().string();
    if (1 + name.size() + suffix.size() > NAME_MAX) name.erase(0, 1 + name.size() + suffix.size() - NAME_MAX);
    std::filesystem::path temporary = path;
    std::string hidden = ".";
    hidden += name;
    hidden += suffix;
    temporary.replace_filename(hidden);
    return temporary;
}

inline std::string stb_failure() {
    const char* reason = stbi_failure_reason();
    return reason ? reason : "unknown reason";
}

// Binary PPM (P6), the output format of the course's 2017-2019 scenes (their cameras name
// `.ppm` images): the same to_8bit bytes a PNG would hold, uncompressed.
// Written in blocks of rows through one small buffer: converting the whole image first took a
// fresh buffer of 2-3.5 MB per course image, whose page faults cost as much as the conversion,
// on the main thread after the render (ocornellbox writes three).
inline void write_ppm(const std::filesystem::path& path, const Image& image, const std::filesystem::path& shown) {
    std::ofstream out(path, std::ios::binary);
    out << "P6\n" << image.width << ' ' << image.height << "\n255\n";
    const std::size_t row = std::size_t(image.width) * 3;
    const std::size_t block_rows = std::max<std::size_t>(1, (std::size_t(64) << 10) / row);
    std::vector<std::uint8_t> bytes;
    for (std::size_t y = 0; y < std::size_t(image.height) && out; y += block_rows) {
        const std::size_t rows = std::min(block_rows, std::size_t(image.height) - y);
        static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "the rows are read as packed floats");
        const float* channels = &image.pixels[y * std::size_t(image.width)].x;
        bytes.resize(rows * row);
        for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = channel_to_8bit(channels[i]);
        out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    }
    out.close();
    if (!out) throw io::LoadError(shown, "ImageName", "cannot write the PPM file");
}

// A file encoded whole (png_encoder.hpp, exr_encoder.hpp), written out.
inline bool write_encoded(const std::filesystem::path& path, const std::optional<std::vector<std::uint8_t>>& file) {
    if (!file) return false;
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(file->data()), std::streamsize(file->size()));
    out.close();
    return bool(out);
}

}  // namespace detail

// Why write_image cannot write `path`'s format, or nothing when it can: its extension, in any
// case, must be .png, .exr or .ppm. Callers that render check it first (prism checks every
// camera's outputs before the render), so a name's typo costs no render time.
inline std::optional<std::string> unwritable_format(const std::filesystem::path& path) {
    const std::string extension = detail::lowercase_extension(path);
    if (extension == ".png" || extension == ".exr" || extension == ".ppm") return std::nullopt;
    return "unsupported output format '" + extension + "' (use .png, .exr or .ppm)";
}

// Writes `.png` or `.ppm` (8-bit, to_8bit) or `.exr` (linear float RGB). Missing parent folders are
// created; the file appears whole or not at all (written to a temporary sibling, then renamed),
// so a failed or interrupted write never leaves a truncated image that looks like a result.
inline void write_image(const std::filesystem::path& path, const Image& image) {
    const std::string extension = detail::lowercase_extension(path);
    if (const std::optional<std::string> problem = unwritable_format(path)) throw io::LoadError(path, "ImageName", *problem);
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != std::size_t(image.width) * std::size_t(image.height))
        throw io::LoadError(path, "ImageName", "the image is empty or its size does not match its pixels");

    std::error_code error;
    if (path.has_parent_path()) {
        std::filesystem::create_directories(path.parent_path(), error);
        if (error) throw io::LoadError(path, "ImageName", "cannot create the folder: " + error.message());
    }
    const std::filesystem::path temporary = detail::temporary_sibling(path);
    try {
        if (extension == ".png") {
            if (!detail::write_encoded(temporary, encode_png(image)))
                throw io::LoadError(path, "ImageName", "cannot write the PNG file");
        } else if (extension == ".ppm") {
            detail::write_ppm(temporary, image, path);
        } else {
            if (!detail::write_encoded(temporary, encode_exr(image)))
                throw io::LoadError(path, "ImageName", "cannot write the EXR file");
        }
        std::filesystem::rename(temporary, path, error);
        if (error) throw io::LoadError(path, "ImageName", "cannot replace the file: " + error.message());
    } catch (...) {
        std::filesystem::remove(temporary, error);
        throw;
    }
}

namespace detail {

// The image's size, checked against the limits before anything is decoded: a file's header can
// claim any size, and the decoders would allocate it.
inline void check_image_size(const std::filesystem::path& path, std::int64_t width, std::int64_t height,
                             std::int64_t max_pixels) {
    if (width <= 0 || height <= 0)
        throw io::LoadError(path, "", "the image has no pixels (" + std::to_string(width) + " x " +
                                          std::to_string(height) + ")");
    if (width > io::max_image_side || height > io::max_image_side || width * height > max_pixels)
        throw io::LoadError(path, "", "the image is " + std::to_string(width) + " x " + std::to_string(height) +
                                          " pixels; prism reads at most " + std::to_string(io::max_image_side) +
                                          " per side and " + std::to_string(max_pixels) + " in all");
}

// An OpenEXR file's header, parsed into `header` (initialised by the caller, freed by it on
// success and here on failure) with its data window checked against the limits: what decode_exr
// and image_extent read first.
inline void read_exr_header(std::string_view bytes, const std::filesystem::path& path, std::int64_t max_pixels,
                            EXRVersion& version, EXRHeader& header) {
    const auto* memory = reinterpret_cast<const unsigned char*>(bytes.data());
    if (ParseEXRVersionFromMemory(&version, memory, bytes.size()) != TINYEXR_SUCCESS)
        throw io::LoadError(path, "", "not an OpenEXR file");
    if (version.multipart || version.non_image) throw io::LoadError(path, "", "multi-part and deep EXR files are not supported");
    const char* message = nullptr;
    if (ParseEXRHeaderFromMemory(&header, &version, memory, bytes.size(), &message) != TINYEXR_SUCCESS) {
        FreeEXRHeader(&header);
        const std::string what = message ? message : "cannot read the EXR header";
        if (message) FreeEXRErrorMessage(message);
        throw io::LoadError(path, "", what);
    }
    try {
        check_image_size(path, std::int64_t(header.data_window.max_x) - header.data_window.min_x + 1,
                         std::int64_t(header.data_window.max_y) - header.data_window.min_y + 1, max_pixels);
    } catch (...) {
        FreeEXRHeader(&header);
        throw;
    }
}

// OpenEXR through tinyexr's header-then-image calls (not LoadEXRFromMemory), so that the data
// window is checked before the pixels are allocated and every path frees what tinyexr allocated.
inline Image decode_exr(std::string_view bytes, const std::filesystem::path& path, std::int64_t max_pixels) {
    const auto* memory = reinterpret_cast<const unsigned char*>(bytes.data());
    const char* message = nullptr;
    const auto fail = [&](const char* fallback) {
        const std::string what = message ? message : fallback;
        if (message) FreeEXRErrorMessage(message);
        return io::LoadError(path, "", what);
    };
    EXRVersion version;
    EXRHeader header;
    InitEXRHeader(&header);
    read_exr_header(bytes, path, max_pixels, version, header);
    struct HeaderGuard {
        EXRHeader& header;
        ~HeaderGuard() { FreeEXRHeader(&header); }
    } header_guard{header};
    int channel_of[3] = {-1, -1, -1};  // R, G, B; a single channel (Y or anything) is grey
    for (int c = 0; c < header.num_channels; ++c) {
        if (header.pixel_types[c] == TINYEXR_PIXELTYPE_HALF) header.requested_pixel_types[c] = TINYEXR_PIXELTYPE_FLOAT;
        const std::string_view name = header.channels[c].name;
        if (name == "R") channel_of[0] = c;
        else if (name == "G") channel_of[1] = c;
        else if (name == "B") channel_of[2] = c;
    }
    if (header.num_channels == 1) channel_of[0] = channel_of[1] = channel_of[2] = 0;
    if (channel_of[0] < 0 || channel_of[1] < 0 || channel_of[2] < 0)
        throw io::LoadError(path, "", "the EXR file has no R, G and B channels");
    for (int c : channel_of)
        if (header.requested_pixel_types[c] != TINYEXR_PIXELTYPE_FLOAT)
            throw io::LoadError(path, "", "the EXR file's colour channels are not floating point");

    EXRImage exr;
    InitEXRImage(&exr);
    // On failure tinyexr frees the image itself, leaving its pointers dangling: no FreeEXRImage
    // here. Its scanline decoder sets num_channels only on success, so its own clean-up would
    // free no channel buffer of a file that fails half-way (a leak found by fuzzing); setting the
    // count first lets it free them.
    exr.num_channels = header.num_channels;
    if (LoadEXRImageFromMemory(&exr, &header, memory, bytes.size(), &message) != TINYEXR_SUCCESS)
        throw fail("cannot read the EXR file");
    struct ImageGuard {
        EXRImage& exr;
        ~ImageGuard() { FreeEXRImage(&exr); }
    } image_guard{exr};
    Image image;
    image.width = exr.width;
    image.height = exr.height;
    check_image_size(path, image.width, image.height, max_pixels);
    // Black where no tile lands (the film's allocator leaves resized pixels unset).
    image.pixels.assign(std::size_t(image.width) * std::size_t(image.height), glm::vec3(0.0f));
    const auto store = [&](float* const* planes, int width, int height, int x0, int y0) {
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                if (x0 + x >= image.width || y0 + y >= image.height) continue;
                const std::size_t source = std::size_t(y) * std::size_t(width) + std::size_t(x);
                image.pixels[std::size_t(y0 + y) * std::size_t(image.width) + std::size_t(x0 + x)] =
                    glm::vec3(planes[channel_of[0]][source], planes[channel_of[1]][source], planes[channel_of[2]][source]);
            }
    };
    if (header.tiled) {
        for (int t = 0; t < exr.num_tiles; ++t) {
            const EXRTile& tile = exr.tiles[t];
            store(reinterpret_cast<float* const*>(tile.images), header.tile_size_x, header.tile_size_y,
                  tile.offset_x * header.tile_size_x, tile.offset_y * header.tile_size_y);
        }
    } else {
        store(reinterpret_cast<float* const*>(exr.images), image.width, image.height, 0, 0);
    }
    return image;
}

}  // namespace detail

namespace detail {

inline bool is_ldr_extension(const std::string& extension) {
    return extension == ".png" || extension == ".jpg" || extension == ".jpeg" || extension == ".bmp" ||
           extension == ".tga" || extension == ".ppm" || extension == ".pgm";
}

// A file stb decodes (an 8-bit format or .hdr), after the checks every such file passes first
// (its size among them, read from its header): its bytes as stb takes them.
struct StbInput {
    const stbi_uc* memory = nullptr;
    int length = 0;
    int width = 0, height = 0;  // from the header
};
inline StbInput checked_stb_input(std::string_view bytes, const std::filesystem::path& path,
                                  const std::string& extension, std::int64_t max_pixels) {
    if (!is_ldr_extension(extension) && extension != ".hdr")
        throw io::LoadError(path, "", "unsupported image format '" + extension + "'");
    if (!has_signature_of(bytes, extension))
        throw io::LoadError(path, "", "the file's content is not the " + extension.substr(1) + " image its name says");
    if ((extension == ".jpg" || extension == ".jpeg") && !jpeg_huffman_tables_fit(bytes))
        throw io::LoadError(path, "", "corrupt JPEG: a Huffman table of more than 256 codes");
    if ((extension == ".ppm" || extension == ".pgm") && !pnm_header_fits(bytes))
        throw io::LoadError(path, "", "unsupported PNM header: a number past 2147483647 or 16-bit samples");
    // stb takes an int length.
    if (bytes.size() > std::size_t(std::numeric_limits<int>::max()))
        throw io::LoadError(path, "", "the file is larger than 2 GiB");
    StbInput input{reinterpret_cast<const stbi_uc*>(bytes.data()), int(bytes.size())};
    int channels = 0;
    if (!stbi_info_from_memory(input.memory, input.length, &input.width, &input.height, &channels))
        throw io::LoadError(path, "", "cannot read the image: " + stb_failure());
    check_image_size(path, input.width, input.height, max_pixels);
    return input;
}

// stb's decoded samples, RGB, freed by stb.
template <class Sample>
struct StbSamples {
    struct Free {
        void operator()(Sample* samples) const { stbi_image_free(samples); }
    };
    std::unique_ptr<Sample, Free> samples;
    int width = 0, height = 0;
};
// stbi_load for 8-bit files, not stbi_loadf: stbi_loadf would undo an assumed 2.2 gamma, while
// the suite needs the stored byte values unchanged. stbi_loadf for .hdr: linear radiance must
// not be squeezed to 8 bits.
template <class Sample>
StbSamples<Sample> stb_decode(std::string_view bytes, const std::filesystem::path& path, const std::string& extension,
                              std::int64_t max_pixels) {
    const StbInput input = checked_stb_input(bytes, path, extension, max_pixels);
    StbSamples<Sample> decoded;
    int channels = 0;
    if constexpr (std::is_same_v<Sample, float>)
        decoded.samples.reset(stbi_loadf_from_memory(input.memory, input.length, &decoded.width, &decoded.height, &channels, 3));
    else
        decoded.samples.reset(stbi_load_from_memory(input.memory, input.length, &decoded.width, &decoded.height, &channels, 3));
    if (!decoded.samples) throw io::LoadError(path, "", "cannot read the image: " + stb_failure());
    return decoded;
}

}  // namespace detail

// Decodes an image file's bytes already in memory into linear floats on the renderer's scale:
// 8-bit formats give 0..255 (the values the course's PNGs hold), .hdr and .exr their stored
// radiance unchanged. The extension of `path` chooses the format; `path` names the file in
// messages. Images past io::max_image_side per side or `max_pixels` in all are refused unread.
inline Image decode_image(std::string_view bytes, const std::filesystem::path& path,
                          std::int64_t max_pixels = io::max_image_pixels) {
    const std::string extension = detail::lowercase_extension(path);
    if (extension == ".exr") return detail::decode_exr(bytes, path, max_pixels);
    // Default-initialised pixels, converted in runs on TBB's threads: the fresh pages' first
    // touch is most of this loop's time (the kernel zeroes each page on first touch); in runs,
    // both threads take their share of the faults.
    const auto widened = [](const auto& decoded) {
        Image image(decoded.width, decoded.height, Image::Unfilled{});
        const auto* data = decoded.samples.get();
        for_each_run(image.pixels.size(), image_pass_grain, [&](std::size_t first, std::size_t end) {
            for (std::size_t i = first; i < end; ++i)
                image.pixels[i] = glm::vec3(float(data[3 * i]), float(data[3 * i + 1]), float(data[3 * i + 2]));
        });
        return image;
    };
    if (extension == ".hdr") return widened(detail::stb_decode<float>(bytes, path, extension, max_pixels));
    return widened(detail::stb_decode<stbi_uc>(bytes, path, extension, max_pixels));
}

// The same file as a texture's texels (image/texels.hpp): an 8-bit file's bytes as decoded, never
// widened to floats; .hdr and .exr as decode_image gives them. The same checks and messages.
inline Texels decode_texels(std::string_view bytes, const std::filesystem::path& path,
                            std::int64_t max_pixels = io::max_image_pixels) {
    const std::string extension = detail::lowercase_extension(path);
    if (!detail::is_ldr_extension(extension)) return Texels(decode_image(bytes, path, max_pixels));
    const detail::StbSamples<stbi_uc> decoded = detail::stb_decode<stbi_uc>(bytes, path, extension, max_pixels);
    // Copied out of stb's buffer into huge pages (memory/huge_page_allocator.hpp), in runs on
    // TBB's threads. Lookups land anywhere in a photograph: read from stb's 4 kB pages, nearly
    // every one missed the TLB, and MipMap::lookup took 19% of hw7 VeachAjar's profile at
    // --scale 0.25 (perf, one thread) where from huge pages of floats it had taken under 5%.
    // From half a huge page on, the array is rounded up to whole huge pages (the allocator
    // rounds from one): hw4's earth.jpg, 1.5 MB of bytes, took 5.0-5.2 ms to read in 4 kB pages
    // against 3.4-3.6 ms in a huge page (prism_texture_bench, decode).
    const std::size_t size = 3 * std::size_t(decoded.width) * std::size_t(decoded.height);
    constexpr std::size_t huge_page = HugePageAllocator<std::uint8_t>::huge_page;
    auto storage = std::make_shared<HugePageVector<std::uint8_t>>();
    if (size >= huge_page / 2) storage->reserve((size + huge_page - 1) / huge_page * huge_page);
    storage->resize(size);
    const stbi_uc* data = decoded.samples.get();
    for_each_run(size, 3 * image_pass_grain, [&](std::size_t first, std::size_t end) {
        std::copy(data + first, data + end, storage->data() + first);
    });
    return Texels(Texels::Bytes{decoded.width, decoded.height, std::shared_ptr<const std::uint8_t>(storage, storage->data())});
}

// An image file's size from its header, after the checks decode_image and decode_texels make
// first (the format its name says, the size limits); nothing is decoded. `texel_bytes`: what a
// texel of it takes as decode_texels stores it (8-bit files their 3 bytes, .hdr and .exr 3 floats).
struct ImageExtent {
    std::int64_t width = 0, height = 0;
    std::uint64_t texel_bytes = 0;
};
inline ImageExtent image_extent(std::string_view bytes, const std::filesystem::path& path,
                                std::int64_t max_pixels = io::max_image_pixels) {
    const std::string extension = detail::lowercase_extension(path);
    if (extension == ".exr") {
        EXRVersion version;
        EXRHeader header;
        InitEXRHeader(&header);
        detail::read_exr_header(bytes, path, max_pixels, version, header);
        const ImageExtent extent{std::int64_t(header.data_window.max_x) - header.data_window.min_x + 1,
                                 std::int64_t(header.data_window.max_y) - header.data_window.min_y + 1, 3 * sizeof(float)};
        FreeEXRHeader(&header);
        return extent;
    }
    const detail::StbInput input = detail::checked_stb_input(bytes, path, extension, max_pixels);
    return {input.width, input.height, detail::is_ldr_extension(extension) ? 3u : 3 * sizeof(float)};
}

// Reads an image file (see decode_image).
inline Image read_image(const std::filesystem::path& path) { return decode_image(io::read_regular_file(path, "", "image file"), path); }

// Reads a texture's image file (see decode_texels), as read_image reads one.
inline Texels read_texels(const std::filesystem::path& path) {
    return decode_texels(io::read_regular_file(path, "", "image file"), path);
}

}  // namespace prism
