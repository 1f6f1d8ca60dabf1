// What an image file must be before stb_image sees it. stb recognises a format by its content, not
// its name, and Debian 12's build (libstb 0.0~git20220908, stb_image 2.27) decodes GIF, PSD and
// PIC as well: code prism never needs, open to any file named `.png`. So a file's content must be
// the format its extension names (every one of the course's 156 image files is). And that build
// has a JPEG bug found by fuzzing prism (tests/data/fuzz/image/jpeg_huffman_table_overflow.jpg):
// a DHT segment whose 16 code counts add up past 256 overflows the Huffman table's arrays in
// stbi__build_huffman (later stb_image releases refuse such a table), so those are refused here.
#pragma once

#include <cstddef>
#include <cstdint>
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
        while (remaining > 0 && table + 17 <= bytes.size()) {
            std::size_t codes = 0;
            for (std::size_t k = 1; k <= 16; ++k) codes += byte(table + k);
            if (codes > 256) return false;
            table += 17 + codes;
            remaining -= long(17 + codes);
        }
        i = table;
    }
    return true;
}

}  // namespace prism::detail
