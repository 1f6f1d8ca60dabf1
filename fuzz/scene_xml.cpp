// libFuzzer harness: an XML scene file's bytes through pugixml, the element tree and the
// interpreter to the scene description. Every failure must be a LoadError; anything else that
// escapes (another exception, a sanitizer report, a crash) is a finding.
#include "scene_harness.hpp"

#include <prism/io/xml_reader.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    prism::fuzz::interpret(data, size, ".xml", [](std::string_view text, const std::filesystem::path& path) {
        return prism::io::parse_xml(text, path);
    });
    return 0;
}
