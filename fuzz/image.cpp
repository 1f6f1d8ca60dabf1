// libFuzzer harness: an image file's bytes through decode_image and through decode_texels, the
// texture loader's decoder (stb for PNG/JPEG/BMP/TGA/PNM and Radiance .hdr, tinyexr for OpenEXR).
// The format follows the bytes' magic number, as a file's extension would choose it (TGA has
// none). Images are capped at 2^12 pixels here instead of 2^27, so that the fuzzer spends its
// time on the decoders' logic, not on filling large allocations. A LoadError is the one allowed
// way to fail.
#include <prism/image/image_io.hpp>
#include <prism/io/load_error.hpp>

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    const char* name = bytes.starts_with("\x76\x2f\x31\x01") ? "fuzz.exr"
                       : bytes.starts_with("#?")               ? "fuzz.hdr"
                       : bytes.starts_with("\x89PNG")          ? "fuzz.png"
                       : bytes.starts_with("\xFF\xD8")         ? "fuzz.jpg"
                       : bytes.starts_with("BM")               ? "fuzz.bmp"
                       : bytes.starts_with("P")                ? "fuzz.ppm"
                                                               : "fuzz.tga";
    try {
        const prism::Image image = prism::decode_image(bytes, name, std::int64_t(1) << 12);
        (void)image;
    } catch (const prism::io::LoadError&) {
    }
    // The same bytes as a texture's texels (8-bit files kept as bytes): the same checks, read back.
    try {
        const prism::Texels texels = prism::decode_texels(bytes, name, std::int64_t(1) << 12);
        if (!texels.empty()) (void)texels(texels.width() - 1, texels.height() - 1);
    } catch (const prism::io::LoadError&) {
    }
    return 0;
}
