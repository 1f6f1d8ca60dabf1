// PLY reader (ASCII, binary little and big endian). PLACEHOLDER: the real reader replaces the
// body of read_ply; the interface below is fixed.
#pragma once

#include <prism/io/load_error.hpp>

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace prism::io {

struct PlyMesh {
    std::vector<glm::dvec3> positions;
    std::vector<glm::dvec3> normals;  // empty, or one per vertex
    std::vector<glm::dvec2> uvs;      // empty, or one per vertex
    std::vector<std::array<std::uint32_t, 3>> triangles;  // quads and polygons fanned
};

inline PlyMesh read_ply(const std::filesystem::path& path) {
    throw LoadError(path, "", "PLY reader not implemented yet");
}

}  // namespace prism::io
