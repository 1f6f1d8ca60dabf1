// Image files: the course's 8-bit conversion, writing PNG, PPM and EXR, reading PNG/JPG/BMP/TGA/PPM,
// Radiance .hdr and OpenEXR (scanline or tiled) into the HDR film. stb and tinyexr are compiled
// in their system libraries (libstb, libtinyexr), so no *_IMPLEMENTATION macro is defined here.
#pragma once

#include <prism/image/image.hpp>
#include <prism/io/load_error.hpp>

#include <stb_image.h>
#include <stb_image_write.h>
#include <tinyexr.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

namespace prism {

// The course's LDR conversion when a scene declares no tone mapping: radiance is already on the
// 0..255 scale, so each channel is clamped and truncated, as the course's own renderer does (its
// expected images sit 0.47 levels below rounded ones on average: measured on bunny_with_plane,
// 1024x1024, where everything else matches to within 1/255). NaN becomes 0 (the comparison
// below is false for NaN), so a broken pixel shows as black instead of undefined behaviour.
// Interleaved RGB, row-major from the top-left pixel, as stbi_write_png expects.
inline std::vector<std::uint8_t> to_8bit(const Image& image) {
    std::vector<std::uint8_t> bytes(image.pixels.size() * 3);
    std::size_t i = 0;
    for (const glm::vec3& pixel : image.pixels)
        for (int c = 0; c < 3; ++c) {
            const float value = pixel[c] > 0.0f ? std::min(pixel[c], 255.0f) : 0.0f;
            bytes[i++] = static_cast<std::uint8_t>(value);
        }
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
    std::filesystem::path temporary = path;
    temporary.replace_filename("." + path.filename().string() + "." + std::to_string(::getpid()) + "." +
                               std::to_string(counter++) + ".tmp");
    return temporary;
}

// Float RGB written as three FLOAT channels named B, G, R: EXR viewers expect the channels sorted
// by name, and tinyexr's own SaveEXR does the same. ZIP compression is lossless, so a float
// written is the float read back, bit for bit.
inline void write_exr(const std::filesystem::path& path, const Image& image, const std::filesystem::path& shown) {
    const std::size_t count = image.pixels.size();
    std::vector<float> red(count), green(count), blue(count);
    for (std::size_t i = 0; i < count; ++i) {
        red[i] = image.pixels[i].r;
        green[i] = image.pixels[i].g;
        blue[i] = image.pixels[i].b;
    }
    float* planes[3] = {blue.data(), green.data(), red.data()};

    EXRImage exr_image;
    InitEXRImage(&exr_image);
    exr_image.num_channels = 3;
    exr_image.images = reinterpret_cast<unsigned char**>(planes);
    exr_image.width = image.width;
    exr_image.height = image.height;

    // The header's arrays live on this stack frame, so no FreeEXRHeader: nothing leaks on any path.
    EXRChannelInfo channels[3] = {};
    const char names[3] = {'B', 'G', 'R'};
    for (int c = 0; c < 3; ++c) {
        channels[c].name[0] = names[c];
        channels[c].x_sampling = channels[c].y_sampling = 1;
    }
    int pixel_types[3] = {TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT};
    int requested_pixel_types[3] = {TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT};
    EXRHeader header;
    InitEXRHeader(&header);
    header.num_channels = 3;
    header.channels = channels;
    header.pixel_types = pixel_types;
    header.requested_pixel_types = requested_pixel_types;
    header.compression_type = TINYEXR_COMPRESSIONTYPE_ZIP;

    const char* error = nullptr;
    if (SaveEXRImageToFile(&exr_image, &header, path.c_str(), &error) != TINYEXR_SUCCESS) {
        const std::string message = error ? error : "cannot write the EXR file";
        if (error) FreeEXRErrorMessage(error);
        throw io::LoadError(shown, "ImageName", message);
    }
}

inline std::string stb_failure() {
    const char* reason = stbi_failure_reason();
    return reason ? reason : "unknown reason";
}

// Binary PPM (P6), the output format of the course's 2017-2019 scenes (their cameras name
// `.ppm` images): the same to_8bit bytes a PNG would hold, uncompressed.
inline void write_ppm(const std::filesystem::path& path, const Image& image, const std::filesystem::path& shown) {
    const std::vector<std::uint8_t> bytes = to_8bit(image);
    std::ofstream out(path, std::ios::binary);
    out << "P6\n" << image.width << ' ' << image.height << "\n255\n";
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    out.close();
    if (!out) throw io::LoadError(shown, "ImageName", "cannot write the PPM file");
}

// An 8-bit RGB PNG (PNG specification, ISO/IEC 15948): every row with the Sub filter, one
// zlib stream at zlib's default level. stb's writer tries five filters per row and compresses
// with its own deflate: 214 ms for an 800 x 800 course image here, against 54 ms for this (and
// 29 kB instead of 38 kB); on the small hw1 scenes that was a fifth of the whole process.
inline bool write_png(const std::filesystem::path& path, const std::vector<std::uint8_t>& rgb, int width,
                      int height) {
    const std::size_t row = std::size_t(width) * 3;
    std::vector<std::uint8_t> filtered;
    filtered.reserve((row + 1) * std::size_t(height));
    for (int y = 0; y < height; ++y) {
        const std::uint8_t* line = rgb.data() + std::size_t(y) * row;
        filtered.push_back(1);  // Sub: each byte minus the byte one pixel to its left
        for (std::size_t i = 0; i < row; ++i) filtered.push_back(std::uint8_t(line[i] - (i >= 3 ? line[i - 3] : 0)));
    }
    uLongf compressed_size = compressBound(uLong(filtered.size()));
    std::vector<std::uint8_t> compressed(compressed_size);
    if (compress2(compressed.data(), &compressed_size, filtered.data(), uLong(filtered.size()), Z_DEFAULT_COMPRESSION) !=
        Z_OK)
        return false;
    compressed.resize(compressed_size);

    std::ofstream out(path, std::ios::binary);
    const auto put32 = [&](std::uint32_t value) {
        const std::array<char, 4> bytes{char(value >> 24), char(value >> 16), char(value >> 8), char(value)};
        out.write(bytes.data(), 4);
    };
    const auto chunk = [&](const char* type, const std::uint8_t* data, std::size_t size) {
        put32(std::uint32_t(size));
        out.write(type, 4);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
        uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(type), 4);
        if (size > 0) crc = crc32(crc, data, uInt(size));  // (a null buffer would restart the crc)
        put32(std::uint32_t(crc));
    };
    out.write("\x89PNG\r\n\x1a\n", 8);
    const std::array<std::uint8_t, 13> header{
        std::uint8_t(width >> 24), std::uint8_t(width >> 16), std::uint8_t(width >> 8), std::uint8_t(width),
        std::uint8_t(height >> 24), std::uint8_t(height >> 16), std::uint8_t(height >> 8), std::uint8_t(height),
        8, 2, 0, 0, 0};  // 8 bits, RGB, deflate, adaptive filtering, no interlace
    chunk("IHDR", header.data(), header.size());
    chunk("IDAT", compressed.data(), compressed.size());
    chunk("IEND", nullptr, 0);
    return bool(out);
}

}  // namespace detail

// Writes `.png` or `.ppm` (8-bit, to_8bit) or `.exr` (linear float RGB). Missing parent folders are
// created; the file appears whole or not at all (written to a temporary sibling, then renamed),
// so a failed or interrupted write never leaves a truncated image that looks like a result.
inline void write_image(const std::filesystem::path& path, const Image& image) {
    const std::string extension = detail::lowercase_extension(path);
    if (extension != ".png" && extension != ".exr" && extension != ".ppm")
        throw io::LoadError(path, "ImageName",
                            "unsupported output format '" + extension + "' (use .png, .exr or .ppm)");
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
            const std::vector<std::uint8_t> bytes = to_8bit(image);
            if (!detail::write_png(temporary, bytes, image.width, image.height))
                throw io::LoadError(path, "ImageName", "cannot write the PNG file");
        } else if (extension == ".ppm") {
            detail::write_ppm(temporary, image, path);
        } else {
            detail::write_exr(temporary, image, path);
        }
        std::filesystem::rename(temporary, path, error);
        if (error) throw io::LoadError(path, "ImageName", "cannot replace the file: " + error.message());
    } catch (...) {
        std::filesystem::remove(temporary, error);
        throw;
    }
}

// Reads an image into linear floats on the renderer's scale: 8-bit formats give 0..255 (the
// values the course's PNGs hold), .hdr and .exr give their stored radiance unchanged.
inline Image read_image(const std::filesystem::path& path) {
    const std::string extension = detail::lowercase_extension(path);
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error))
        throw io::LoadError(path, "", "no such image file");

    Image image;
    if (extension == ".exr") {
        float* rgba = nullptr;
        const char* message = nullptr;
        if (LoadEXR(&rgba, &image.width, &image.height, path.c_str(), &message) != TINYEXR_SUCCESS) {
            const std::string what = message ? message : "cannot read the EXR file";
            if (message) FreeEXRErrorMessage(message);
            throw io::LoadError(path, "", what);
        }
        image.pixels.resize(std::size_t(image.width) * std::size_t(image.height));
        for (std::size_t i = 0; i < image.pixels.size(); ++i)
            image.pixels[i] = glm::vec3(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
        std::free(rgba);  // LoadEXR allocates with malloc
        return image;
    }

    const bool is_hdr = extension == ".hdr";
    const bool is_ldr = extension == ".png" || extension == ".jpg" || extension == ".jpeg" || extension == ".bmp" ||
                        extension == ".tga" || extension == ".ppm" || extension == ".pgm";
    if (!is_hdr && !is_ldr) throw io::LoadError(path, "", "unsupported image format '" + extension + "'");

    int channels = 0;
    if (is_hdr) {
        // stbi_loadf, not stbi_load: .hdr holds linear radiance that must not be squeezed to 8 bits.
        float* data = stbi_loadf(path.c_str(), &image.width, &image.height, &channels, 3);
        if (!data) throw io::LoadError(path, "", "cannot read the image: " + detail::stb_failure());
        image.pixels.resize(std::size_t(image.width) * std::size_t(image.height));
        for (std::size_t i = 0; i < image.pixels.size(); ++i)
            image.pixels[i] = glm::vec3(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
        stbi_image_free(data);
    } else {
        // stbi_load, not stbi_loadf: stbi_loadf would undo an assumed 2.2 gamma on 8-bit files,
        // while the suite needs the stored byte values unchanged.
        unsigned char* data = stbi_load(path.c_str(), &image.width, &image.height, &channels, 3);
        if (!data) throw io::LoadError(path, "", "cannot read the image: " + detail::stb_failure());
        image.pixels.resize(std::size_t(image.width) * std::size_t(image.height));
        for (std::size_t i = 0; i < image.pixels.size(); ++i)
            image.pixels[i] = glm::vec3(float(data[3 * i]), float(data[3 * i + 1]), float(data[3 * i + 2]));
        stbi_image_free(data);
    }
    return image;
}

}  // namespace prism
