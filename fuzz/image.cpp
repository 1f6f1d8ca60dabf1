// libFuzzer harness: an image file's bytes through decode_image, the texture loader's decoder
// (stb for PNG/JPEG/BMP/TGA/PNM and Radiance .hdr, tinyexr for OpenEXR). The format follows the
// bytes' magic number, as a file's extension would choose it. Images are capped at 2^16 pixels
// here instead of 2^27, so that the fuzzer spends its time on the decoders' logic, not on
// filling large allocations. A LoadError is the one allowed way to fail.
#include <prism/image/image_io.hpp>
#include <prism/io/load_error.hpp>

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    const char* name = bytes.starts_with("\x76\x2f\x31\x01") ? "fuzz.exr" : bytes.starts_with("#?") ? "fuzz.hdr" : "fuzz.png";
    try {
        const prism::Image image = prism::decode_image(bytes, name, std::int64_t(1) << 16);
        (void)image;
    } catch (const prism::io::LoadError&) {
    }
    return 0;
}
