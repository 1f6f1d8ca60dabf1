// Loads a CENG795 scene file into the plain scene description, choosing the reader by the file's
// extension (.xml: pugixml, .json: nlohmann-json); both feed the same interpreter.
//
// The readers and the interpreter are some 400 kB of code that every file calling load_scene
// compiles (about 19 s of GCC 12 at -O3). A program of several files can compile them once: with
// PRISM_SEPARATE_SCENE_FILES defined for the whole program, this header only declares
// load_scene, and the one file that also defines PRISM_SCENE_FILES_DEFINED_HERE compiles its
// definition (the project's CMake target prism_scene_files, examples/renderers/scene_files.cpp,
// does so for its examples, benchmarks and tests). Header-only users need neither macro.
#pragma once

#include <prism/io/load_error.hpp>  // what load_scene throws
#include <prism/io/load_options.hpp>
#include <prism/scene/scene.hpp>

#include <filesystem>

#if defined(PRISM_SEPARATE_SCENE_FILES) && !defined(PRISM_SCENE_FILES_DEFINED_HERE)

namespace prism::io {

scene::Scene load_scene(const std::filesystem::path& path, const LoadOptions& options = {});

}  // namespace prism::io

#else

#include <prism/io/json_reader.hpp>
#include <prism/io/scene_loader.hpp>
#include <prism/io/xml_reader.hpp>

#include <algorithm>
#include <cctype>
#include <string>

// Inline for header-only use; one ordinary definition where the program compiles it apart.
#ifdef PRISM_SEPARATE_SCENE_FILES
#define PRISM_LOAD_SCENE_LINKAGE
#else
#define PRISM_LOAD_SCENE_LINKAGE inline
#endif

namespace prism::io {

PRISM_LOAD_SCENE_LINKAGE scene::Scene load_scene(const std::filesystem::path& path, const LoadOptions& options = {}) {
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (extension == ".xml") return interpret_scene(read_xml(path), path, options);
    if (extension == ".json") return interpret_scene(read_json(path), path, options);
    throw LoadError(path, "", "unknown scene format \"" + extension + "\": expected a .xml or .json file");
}

}  // namespace prism::io

#undef PRISM_LOAD_SCENE_LINKAGE

#endif
