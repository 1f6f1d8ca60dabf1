// libFuzzer harness: a PLY file's bytes (ASCII or binary, either byte order) through the PLY
// reader. A LoadError is the one allowed way to fail.
#include <prism/io/load_error.hpp>
#include <prism/io/ply.hpp>

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        const prism::io::PlyMesh mesh =
            prism::io::parse_ply(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.ply");
        (void)mesh;
    } catch (const prism::io::LoadError&) {
    }
    return 0;
}
