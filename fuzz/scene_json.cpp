// libFuzzer harness: a JSON scene file's bytes through nlohmann's SAX parser, the element tree and
// the interpreter to the scene description (see scene_harness.hpp for what counts as a finding).
#include "scene_harness.hpp"

#include <prism/io/json_reader.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    prism::fuzz::interpret(data, size, ".json", [](std::string_view text, const std::filesystem::path& path) {
        return prism::io::parse_json(text, path);
    });
    return 0;
}
