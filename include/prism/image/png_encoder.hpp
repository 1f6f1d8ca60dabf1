// The 8-bit PNG of an HDR film (PNG specification, ISO/IEC 15948): the course's 8-bit
// conversion, every row with the Sub filter, deflated in bands of rows on TBB's threads.
// Compression was the largest fixed cost of a small render: zlib's default level took 45 ms for
// hw2 mirror_room's 800 x 800 image on one core, a tenth of the whole process, and 8 ms of
// hw1 simple.xml's 52 ms. The bands make it parallel the way pigz does: each band is a raw
// deflate stream ended by a sync flush (the last by the stream's end), the bands are
// concatenated behind one zlib header, and their Adler-32 sums are combined. The band size is
// fixed, so the file's bytes do not depend on the number of threads.
#pragma once

#include <prism/image/deflate_stream.hpp>
#include <prism/image/image.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace prism {

// The course's LDR conversion of one channel when a scene declares no tone mapping: radiance is
// already on the 0..255 scale, so it is clamped and truncated, as the course's own renderer does
// (its expected images sit 0.47 levels below rounded ones on average: measured on
// bunny_with_plane, 1024x1024, where everything else matches to within 1/255). NaN becomes 0
// (the comparison is false for NaN), so a broken pixel shows as black instead of undefined
// behaviour.
inline std::uint8_t channel_to_8bit(float value) {
    return static_cast<std::uint8_t>(value > 0.0f ? std::min(value, 255.0f) : 0.0f);
}

namespace detail {

// zlib's fastest level. Against the default level (6) on five course images (800 x 800 to
// 1024 x 1024) it takes 0.2-0.4 of the time for files 1.3-1.9 times as large (mirror_room:
// 45.5 ms and 197 kB at level 6, 9.6 ms and 297 kB at level 1); the course's images are
// 80-300 kB either way, and the pixels are the same.
inline constexpr int png_deflate_level = Z_BEST_SPEED;

// Rows per band: about 96 kB of filtered bytes, small enough to stay in cache between the
// conversion and deflate and below glibc's mmap threshold (so a band's buffer is reused, not
// faulted in afresh), and many bands to an image, so two or more threads share the work evenly.
inline int png_band_rows(std::size_t row_bytes) { return std::max(1, int((96u << 10) / (row_bytes + 1))); }

struct DeflatedBand {
    std::vector<std::uint8_t> bytes;
    uLong adler = 0;       // Adler-32 of the band's filtered bytes
    std::size_t size = 0;  // the count of filtered bytes (for adler32_combine)
    bool ok = false;
};

// A thread's buffers and deflate state, kept from band to band: fresh buffers are cleared and
// faulted in again, as a fresh z_stream is (deflate_stream.hpp).
struct BandScratch {
    std::vector<std::uint8_t> row;  // a row's bytes before filtering
    std::vector<std::uint8_t> filtered;
    std::vector<std::uint8_t> deflated;
    DeflateStream stream{png_deflate_level, -15};
};

// Rows [first, last) of `image`, converted, filtered with Sub (each byte minus the byte one
// pixel to its left) and deflated raw; the last band of the image ends the deflate stream.
inline DeflatedBand deflate_band(const Image& image, int first, int last) {
    thread_local BandScratch scratch;
    DeflatedBand band;
    const std::size_t row = std::size_t(image.width) * 3;
    std::vector<std::uint8_t>& filtered = scratch.filtered;
    filtered.resize((row + 1) * std::size_t(last - first));
    // Two straight passes a row, which GCC vectorises: the row's bytes, then their Sub filter.
    // (One pass carrying the left pixel did not vectorise: a one-thread encoding of an 800 x 800
    // test image took 15.8-16.0 ms with it, 12.7-14.4 ms with these, at a load of 9.) glm's vec3
    // is three packed floats, so a row is 3 * width floats.
    std::vector<std::uint8_t>& bytes = scratch.row;
    bytes.resize(row);
    std::uint8_t* out = filtered.data();
    for (int y = first; y < last; ++y) {
        const float* channels = &image.pixels[std::size_t(y) * std::size_t(image.width)].x;
        std::uint8_t* row_bytes = bytes.data();
        for (std::size_t i = 0; i < row; ++i) row_bytes[i] = channel_to_8bit(channels[i]);
        *out++ = 1;  // Sub
        for (std::size_t i = 0; i < std::min<std::size_t>(3, row); ++i) out[i] = row_bytes[i];
        for (std::size_t i = 3; i < row; ++i) out[i] = std::uint8_t(row_bytes[i] - row_bytes[i - 3]);
        out += row;
    }
    band.size = filtered.size();
    band.adler = adler32(adler32(0L, Z_NULL, 0), filtered.data(), uInt(filtered.size()));
    band.ok = scratch.stream.deflate_all(filtered.data(), filtered.size(), last == image.height ? Z_FINISH : Z_SYNC_FLUSH,
                                         scratch.deflated);
    band.bytes = scratch.deflated;
    return band;
}

}  // namespace detail

// The whole PNG file of `image`'s 8-bit conversion (8-bit RGB, no interlace), or nothing if zlib
// fails. The image must be non-empty.
inline std::optional<std::vector<std::uint8_t>> encode_png(const Image& image) {
    const std::size_t row = std::size_t(image.width) * 3;
    const int band_rows = detail::png_band_rows(row);
    const int band_count = (image.height + band_rows - 1) / band_rows;
    std::vector<detail::DeflatedBand> bands(static_cast<std::size_t>(band_count));
    tbb::parallel_for(tbb::blocked_range<int>(0, band_count, 1), [&](const tbb::blocked_range<int>& range) {
        for (int b = range.begin(); b < range.end(); ++b)
            bands[std::size_t(b)] = detail::deflate_band(image, b * band_rows, std::min(image.height, (b + 1) * band_rows));
    });

    std::size_t deflated = 0;
    uLong adler = adler32(0L, Z_NULL, 0);
    for (const detail::DeflatedBand& band : bands) {
        if (!band.ok) return std::nullopt;
        deflated += band.bytes.size();
        adler = adler32_combine(adler, band.adler, z_off_t(band.size));
    }

    std::vector<std::uint8_t> file;
    file.reserve(8 + 25 + 12 + 2 + deflated + 4 + 12);
    const auto put32 = [&](std::uint32_t value) {
        for (int shift = 24; shift >= 0; shift -= 8) file.push_back(std::uint8_t(value >> shift));
    };
    // A chunk's CRC covers its type and data, which are the bytes appended since `start`.
    const auto end_chunk = [&](std::size_t start) {
        const std::uint32_t size = std::uint32_t(file.size() - start - 4);
        for (int i = 0; i < 4; ++i) file[start - 4 + std::size_t(i)] = std::uint8_t(size >> (24 - 8 * i));
        put32(std::uint32_t(crc32(0L, file.data() + start, uInt(file.size() - start))));
    };
    const auto begin_chunk = [&](const char* type) {
        put32(0);  // the size, filled in by end_chunk
        const std::size_t start = file.size();
        file.insert(file.end(), type, type + 4);
        return start;
    };
    const std::uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    file.insert(file.end(), signature, signature + 8);

    std::size_t start = begin_chunk("IHDR");
    put32(std::uint32_t(image.width));
    put32(std::uint32_t(image.height));
    file.insert(file.end(), {8, 2, 0, 0, 0});  // 8 bits, RGB, deflate, adaptive filtering, no interlace
    end_chunk(start);

    start = begin_chunk("IDAT");
    // The zlib header: deflate with a 32 kB window, the fastest level's flag, and a check value
    // that makes the 16-bit header a multiple of 31 (RFC 1950).
    file.insert(file.end(), {0x78, 0x01});
    for (const detail::DeflatedBand& band : bands) file.insert(file.end(), band.bytes.begin(), band.bytes.end());
    put32(std::uint32_t(adler));
    end_chunk(start);

    end_chunk(begin_chunk("IEND"));
    return file;
}

}  // namespace prism
