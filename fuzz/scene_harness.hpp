// What the two scene harnesses share: the bytes are read as a scene file that lives in a folder
// that does not exist, so every PLY, binary data file and image it names is missing (the fuzzer
// must not read the machine's files); a LoadError is the one allowed way to fail.
#pragma once

#include <prism/io/element.hpp>
#include <prism/io/load_error.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace prism::fuzz {

// The element tree through the interpreter to the scene description. Defined once, in
// scene_interpreter.cpp, for both harnesses: the interpreter is most of each harness's compile
// time, and the same code in both.
void interpret_tree(const io::Element& tree, const std::filesystem::path& path);

template <class Parse>
void interpret(const std::uint8_t* data, std::size_t size, const std::string& extension, Parse&& parse) {
    const std::filesystem::path path = "/nonexistent-prism-fuzz/scene" + extension;
    try {
        interpret_tree(parse(std::string_view(reinterpret_cast<const char*>(data), size), path), path);
    } catch (const io::LoadError&) {
        // The expected answer to a broken file.
    }
}

}  // namespace prism::fuzz
