// What the two scene harnesses share: the bytes are read as a scene file that lives in a folder
// that does not exist, so every PLY, binary data file and image it names is missing (the fuzzer
// must not read the machine's files); a LoadError is the one allowed way to fail.
#pragma once

#include <prism/io/load_error.hpp>
#include <prism/io/scene_loader.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace prism::fuzz {

template <class Parse>
void interpret(const std::uint8_t* data, std::size_t size, const std::string& extension, Parse&& parse) {
    const std::filesystem::path path = "/nonexistent-prism-fuzz/scene" + extension;
    try {
        const io::Element tree = parse(std::string_view(reinterpret_cast<const char*>(data), size), path);
        const scene::Scene scene = io::interpret_scene(tree, path);
        (void)scene;
    } catch (const io::LoadError&) {
        // The expected answer to a broken file.
    }
}

}  // namespace prism::fuzz
