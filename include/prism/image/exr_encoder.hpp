// The OpenEXR file of an HDR film: one part, scanlines, three FLOAT channels named B, G, R (EXR
// readers expect the channels sorted by name), ZIP compression (OpenEXR's file layout and its
// ZIP_COMPRESSION: blocks of 16 scanlines, each deflated as one zlib stream after OpenEXR's
// byte split and delta predictor). Lossless: every float read back is the float written, bit
// for bit, NaN payloads and -0 included.
//
// Why not tinyexr's SaveEXR, which the reader still uses: it deflates the blocks one after
// another at zlib's default level, and a 512 x 512 film took it 80-160 ms on the main thread
// after the render, 7% of hw7 path_diffuse's whole process at 16 samples a pixel (eight
// cameras, an EXR each). The blocks are independent streams, so they deflate on TBB's
// threads here, at zlib's fastest level, as the PNG bands do (png_encoder.hpp). The block
// layout is fixed, so the file's bytes do not depend on the number of threads.
#pragma once

#include <prism/image/deflate_stream.hpp>
#include <prism/image/image.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace prism {

namespace detail {

// Scanlines per block of ZIP_COMPRESSION (OpenEXR's ImfCompression.h): the format fixes it.
inline constexpr int exr_block_rows = 16;

// zlib's fastest level, as for the PNG bands. On one core it takes 0.26-0.30 of tinyexr's time
// (the default level) on the course's path-traced references and a photographed environment
// map, for files 1.05-1.12 times as large (bench/image_write_bench.cpp; bench/RESULTS.md,
// "Writing the images"). Run-length or Huffman-only coding was faster still on a noisy
// 16-sample film, but left smooth ones 1.8-3.1 times as large.
inline constexpr int exr_deflate_level = Z_BEST_SPEED;

// The film's floats are copied to the file as they lie in memory; EXR stores little-endian.
static_assert(std::endian::native == std::endian::little, "the EXR encoder writes the film's bytes as they lie");
static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "a pixel is three packed floats");

// A thread's buffers and deflate state, kept from block to block.
struct ExrBlockScratch {
    std::vector<float> raw;               // the block's scanlines, channel by channel
    std::vector<std::uint8_t> predicted;  // split and delta-coded, as ZIP_COMPRESSION deflates them
    std::vector<std::uint8_t> deflated;
    DeflateStream stream{exr_deflate_level, 15};
};

// Rows [first, last) of `image` as one ZIP block's data: deflated, or the raw scanlines where
// deflate would not make them smaller (readers tell the two apart by the size, as OpenEXR's
// own writer stores such a block). Empty if zlib failed.
inline std::vector<std::uint8_t> exr_block(const Image& image, int first, int last) {
    thread_local ExrBlockScratch scratch;
    const std::size_t width = std::size_t(image.width);
    std::vector<float>& raw = scratch.raw;
    raw.resize(3 * width * std::size_t(last - first));
    // Each scanline holds its B, G and R values in turn, each channel a row of floats.
    float* out = raw.data();
    for (int y = first; y < last; ++y) {
        const glm::vec3* row = &image.pixels[std::size_t(y) * width];
        for (int channel = 2; channel >= 0; --channel, out += width)
            for (std::size_t x = 0; x < width; ++x) out[x] = row[x][channel];
    }
    // OpenEXR's ZIP predictor: the even-numbered bytes, then the odd-numbered ones, then each
    // byte replaced by its difference from the one before it, plus 128 (mod 256).
    const std::uint8_t* bytes = reinterpret_cast<const std::uint8_t*>(raw.data());
    const std::size_t size = raw.size() * sizeof(float);
    std::vector<std::uint8_t>& predicted = scratch.predicted;
    predicted.resize(size);
    const std::size_t half = (size + 1) / 2;
    for (std::size_t i = 0; i < half; ++i) predicted[i] = bytes[2 * i];
    for (std::size_t i = 0; i < size / 2; ++i) predicted[half + i] = bytes[2 * i + 1];
    for (std::size_t i = size - 1; i > 0; --i) predicted[i] = std::uint8_t(predicted[i] - predicted[i - 1] + 128);
    if (!scratch.stream.deflate_all(predicted.data(), size, Z_FINISH, scratch.deflated)) return {};
    if (scratch.deflated.size() < size) return scratch.deflated;
    return std::vector<std::uint8_t>(bytes, bytes + size);
}

// Appends little-endian values and header attributes (name, type, size, value) to a file.
struct ExrWriter {
    std::vector<std::uint8_t>& file;
    void bytes(const void* data, std::size_t size) {
        const auto* first = static_cast<const std::uint8_t*>(data);
        file.insert(file.end(), first, first + size);
    }
    void text(std::string_view s) {  // with its terminating zero
        bytes(s.data(), s.size());
        file.push_back(0);
    }
    void i32(std::int32_t value) { bytes(&value, 4); }
    void f32(float value) { bytes(&value, 4); }
    void attribute(std::string_view name, std::string_view type, std::int32_t size) {
        text(name);
        text(type);
        i32(size);
    }
};

}  // namespace detail

// The whole EXR file of `image`, or nothing if zlib fails. The image must be non-empty.
inline std::optional<std::vector<std::uint8_t>> encode_exr(const Image& image) {
    const int block_count = (image.height + detail::exr_block_rows - 1) / detail::exr_block_rows;
    std::vector<std::vector<std::uint8_t>> blocks(static_cast<std::size_t>(block_count));
    tbb::parallel_for(tbb::blocked_range<int>(0, block_count, 1), [&](const tbb::blocked_range<int>& range) {
        for (int b = range.begin(); b < range.end(); ++b)
            blocks[std::size_t(b)] = detail::exr_block(image, b * detail::exr_block_rows,
                                                       std::min(image.height, (b + 1) * detail::exr_block_rows));
    });
    std::size_t data_bytes = 0;
    for (const std::vector<std::uint8_t>& block : blocks) {
        if (block.empty()) return std::nullopt;
        data_bytes += 8 + block.size();
    }

    std::vector<std::uint8_t> file;
    detail::ExrWriter out{file};
    const std::uint8_t magic_and_version[8] = {0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0};  // one part, scanlines
    out.bytes(magic_and_version, 8);
    // The attributes every EXR file has, in name order as OpenEXR writes them.
    const char channel_names[3] = {'B', 'G', 'R'};
    out.attribute("channels", "chlist", 3 * (2 + 16) + 1);
    for (const char name : channel_names) {
        out.text(std::string_view(&name, 1));
        out.i32(2);  // FLOAT
        const std::uint8_t linear_and_reserved[4] = {0, 0, 0, 0};
        out.bytes(linear_and_reserved, 4);
        out.i32(1);  // x sampling
        out.i32(1);  // y sampling
    }
    file.push_back(0);
    out.attribute("compression", "compression", 1);
    file.push_back(3);  // ZIP_COMPRESSION
    for (const char* window : {"dataWindow", "displayWindow"}) {
        out.attribute(window, "box2i", 16);
        out.i32(0);
        out.i32(0);
        out.i32(image.width - 1);
        out.i32(image.height - 1);
    }
    out.attribute("lineOrder", "lineOrder", 1);
    file.push_back(0);  // INCREASING_Y
    out.attribute("pixelAspectRatio", "float", 4);
    out.f32(1.0f);
    out.attribute("screenWindowCenter", "v2f", 8);
    out.f32(0.0f);
    out.f32(0.0f);
    out.attribute("screenWindowWidth", "float", 4);
    out.f32(1.0f);
    file.push_back(0);  // the header's end

    // The offset table: where each block starts, from the file's first byte.
    std::uint64_t offset = file.size() + 8 * blocks.size();
    file.reserve(std::size_t(offset) + data_bytes);
    for (const std::vector<std::uint8_t>& block : blocks) {
        out.bytes(&offset, 8);
        offset += 8 + block.size();
    }
    for (std::size_t b = 0; b < blocks.size(); ++b) {
        out.i32(std::int32_t(b) * detail::exr_block_rows);  // the block's first scanline
        out.i32(std::int32_t(blocks[b].size()));
        out.bytes(blocks[b].data(), blocks[b].size());
    }
    return file;
}

}  // namespace prism
