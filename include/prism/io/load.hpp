// Loads a CENG795 scene file into the plain scene description, choosing the reader by the file's
// extension (.xml: pugixml, .json: nlohmann-json); both feed the same interpreter.
#pragma once

#include <prism/io/json_reader.hpp>
#include <prism/io/load_error.hpp>
#include <prism/io/scene_loader.hpp>
#include <prism/io/xml_reader.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace prism::io {

inline scene::Scene load_scene(const std::filesystem::path& path, const LoadOptions& options = {}) {
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (extension == ".xml") return interpret_scene(read_xml(path), path, options);
    if (extension == ".json") return interpret_scene(read_json(path), path, options);
    throw LoadError(path, "", "unknown scene format \"" + extension + "\": expected a .xml or .json file");
}

}  // namespace prism::io
