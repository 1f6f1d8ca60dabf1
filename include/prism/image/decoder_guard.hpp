// What an image file must be before stb_image sees it. stb recognises a format by its content, not
// its name, and Debian 12's build (libstb 0.0~git20220908, stb_image 2.27) decodes GIF, PSD and
// PIC as well: code prism never needs, open to any file named `.png`. So a file's content must be
// the format its extension names (every one of the course's 156 image files is). And that build
// has a JPEG bug found by fuzzing prism (tests/data/fuzz/image/jpeg_huffman_table_overflow.jpg):
// a DHT segment whose 16 code counts add up past 256 overflows the Huffman table's arrays in
// stbi__build_huffman (later stb_image releases refuse such a table), so those are refused here;
// so are PNM headers whose numbers overflow stb's int, and 16-bit PNMs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

namespace prism::detail {

// Whether `bytes` start as the format of `extension` (lowercase, with its dot) says. TGA has no
// signature: a .tga file must only not look like any other format stb knows.
inline bool has_signature_of(std::string_view bytes, const std::string& extension) {
    const auto png = bytes.starts_with("\x89PNG\r\n\x1a\n");
    const auto jpeg = bytes.starts_with("\xFF\xD8");
    const auto bmp = bytes.starts_with("BM");
    const auto pnm = bytes.starts_with("P5") || bytes.starts_with("P6");
    const auto hdr = bytes.starts_with("#?");
    if (extension == ".png") return png;
    if (extension == ".jpg" || extension == ".jpeg") return jpeg;
    if (extension == ".bmp") return bmp;
    if (extension == ".ppm" || extension == ".pgm") return pnm;
    if (extension == ".hdr") return hdr;
    if (extension == ".tga") {
        // stb takes 0xFF bytes before a JPEG's start-of-image marker as fill, so any leading 0xFF
        // may be a JPEG (found by fuzzing: tests/data/fuzz/image/jpeg_after_fill_bytes.tga).
        const bool other = png || bmp || pnm || hdr || bytes.starts_with("\xFF") || bytes.starts_with("GIF8") ||
                           bytes.starts_with("8BPS") || bytes.starts_with("\x53\x80\xF6\x34");
        return !other;
    }
    return false;
}

// False when a DHT segment of the JPEG `bytes` defines a Huffman table of more than 256 codes.
// Walks the markers as stb reads them: a segment's length skips it, except a DHT's, which stb
// reads table by table for as long as the length says; between scans, entropy-coded bytes are
// skipped up to the next marker.
inline bool jpeg_huffman_tables_fit(std::string_view bytes) {
    const auto byte = [&](std::size_t i) { return std::uint8_t(bytes[i]); };
    std::size_t i = 2;  // past the start-of-image marker
    while (i + 4 <= bytes.size()) {
        if (byte(i) != 0xFF) {
            ++i;
            continue;
        }
        const std::uint8_t marker = byte(i + 1);
        if (marker == 0xFF) {  // fill byte before a marker
            ++i;
            continue;
        }
        // A stuffed zero, a restart marker or TEM: two bytes, no length. End of image: done.
        if (marker == 0x00 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
            i += 2;
            continue;
        }
        if (marker == 0xD9) break;
        const std::size_t length = std::size_t(byte(i + 2)) << 8 | byte(i + 3);
        if (marker != 0xC4) {
            i += 2 + length;
            continue;
        }
        std::size_t table = i + 4;
        long remaining = long(length) - 2;
        // stb reads zeros past the end of the file, so counts cut off by it count as read.
        while (remaining > 0 && table < bytes.size()) {
            std::size_t codes = 0;
            for (std::size_t k = 1; k <= 16 && table + k < bytes.size(); ++k) codes += byte(table + k);
            if (codes > 256) return false;
            table += 17 + codes;
            remaining -= long(17 + codes);
        }
        i = table;
    }
    return true;
}

// False when a PNM header (P5 or P6) holds a number past INT_MAX, or a maximum value past 255.
// stb_image 2.27 reads the numbers into an int with no overflow check (signed overflow), and its
// 16-bit PNM path reads past the buffer it allocated (both found by fuzzing:
// tests/data/fuzz/image/pnm_header_number_overflow.ppm, pnm_16_bit_overflow.ppm); the course has
// no PNM image at all. The header is read as stb reads it: whitespace and `#` comments, then
// width, height and maximum value; a byte past the end reads as 0, and the last byte of the file
// ends a number without joining it.
inline bool pnm_header_fits(std::string_view bytes) {
    std::size_t position = 2;  // past P5 or P6
    const auto at_end = [&] { return position >= bytes.size(); };
    const auto next = [&]() -> char { return at_end() ? '\0' : bytes[position++]; };
    const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r'; };
    char c = next();
    std::int64_t value = 0;
    for (int number = 0; number < 3; ++number) {
        for (;;) {
            while (!at_end() && is_space(c)) c = next();
            if (at_end() || c != '#') break;
            while (!at_end() && c != '\n' && c != '\r') c = next();
        }
        value = 0;
        while (!at_end() && c >= '0' && c <= '9') {
            value = value * 10 + (c - '0');
            if (value > std::numeric_limits<int>::max()) return false;
            c = next();
        }
    }
    return value <= 255;  // the maximum value, read last
}

}  // namespace prism::detail
