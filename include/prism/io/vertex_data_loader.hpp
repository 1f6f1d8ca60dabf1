// The vertices a scene file's objects index (<VertexData>, <TexCoordData>: inline or in a
// binaryFile) and the faces that index them (<Faces>: inline, binaryFile or plyFile), made into
// each mesh's own vertex list.
#pragma once

#include <prism/io/binary_data.hpp>
#include <prism/io/element.hpp>
#include <prism/io/element_reader.hpp>
#include <prism/io/load_error.hpp>
#include <prism/io/ply.hpp>
#include <prism/scene/scene.hpp>

#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

namespace prism::io::detail::scene_loader {

class VertexDataLoader {
public:
    explicit VertexDataLoader(ElementReader& reader) : reader_(reader) {}

    // Reads the element's binaryFile (resolved against the scene's folder) with one of the
    // read_binary_* readers; their errors name the binary file, this adds the element.
    template <class Read>
    auto read_binary_file(const Element& element, Read&& read) const {
        const std::filesystem::path path = reader_.folder() / std::string(trim(*element.attribute("binaryFile")));
        try {
            return read(path);
        } catch (const LoadError& error) {
            throw LoadError(reader_.file(), element.where(), error.what());
        }
    }

    void read_vertex_data(const Element& element) {
        if (const std::string* type = element.attribute("type"); type != nullptr && trim(*type) != "xyz")
            reader_.fail(element, "unsupported vertex data type " + in_quotes(*type) + " (expected \"xyz\")");
        const std::vector<double> v =
            element.attribute("binaryFile") != nullptr
                ? read_binary_file(element, [](const auto& path) { return read_binary_floats(path, 3, "vertex data"); })
                : reader_.numbers(element);
        if (v.size() % 3 != 0)
            reader_.fail(element, std::to_string(v.size()) + " numbers do not make x y z triples");
        vertices_.reserve(v.size() / 3);
        for (std::size_t i = 0; i < v.size(); i += 3) vertices_.push_back({v[i], v[i + 1], v[i + 2]});
    }

    void read_texture_coordinates(const Element& element) {
        const std::vector<double> v =
            element.attribute("binaryFile") != nullptr
                ? read_binary_file(element,
                                    [](const auto& path) { return read_binary_floats(path, 2, "texture coordinates"); })
                : reader_.numbers(element);
        if (v.size() % 2 != 0) reader_.fail(element, std::to_string(v.size()) + " numbers do not make u v pairs");
        texture_coordinates_.reserve(v.size() / 2);
        for (std::size_t i = 0; i < v.size(); i += 2) texture_coordinates_.push_back({v[i], v[i + 1]});
    }

    // A 1-based index into VertexData, as Sphere's Center and Plane's Point give it.
    scene::Vec3 vertex_of(const Element& reference) const {
        const long long index = reader_.integer(reference);
        if (index < 1 || std::size_t(index) > vertices_.size())
            reader_.fail(reference, "vertex index " + std::to_string(index) + " is out of range: the VertexData holds " +
                                        std::to_string(vertices_.size()) + " vertices (indices start at 1)");
        return vertices_[std::size_t(index - 1)];
    }

    // Builds one mesh's own vertex list from global indices: each global vertex (with its
    // texture coordinate, when the scene has them) becomes one local vertex, so faces that share a
    // vertex in the file share it in the mesh.
    struct MeshBuilder {
        scene::Mesh& mesh;
        std::unordered_map<std::uint64_t, std::uint32_t> local_index{};
    };

    void add_indexed_faces(MeshBuilder& builder, const Element& element, const std::vector<long long>& indices,
                           long long vertex_offset, long long texture_offset) const {
        if (indices.size() % 3 != 0)
            reader_.fail(element, std::to_string(indices.size()) + " vertex indices do not make triangles");
        const bool with_uvs = !texture_coordinates_.empty();
        const auto local = [&](long long written) -> std::uint32_t {
            const long long vertex = written + vertex_offset;
            if (vertex < 1 || std::size_t(vertex) > vertices_.size())
                reader_.fail(element, "vertex index " + std::to_string(vertex) +
                                          (vertex_offset != 0 ? " (" + std::to_string(written) + " + vertexOffset " +
                                                                    std::to_string(vertex_offset) + ")"
                                                              : std::string()) +
                                          " is out of range: the VertexData holds " + std::to_string(vertices_.size()) +
                                          " vertices (indices start at 1)");
            const long long uv = written + texture_offset;
            if (with_uvs && (uv < 1 || std::size_t(uv) > texture_coordinates_.size()))
                reader_.fail(element, "texture coordinate index " + std::to_string(uv) +
                                          " is out of range: the TexCoordData holds " +
                                          std::to_string(texture_coordinates_.size()) + " pairs");
            const std::uint64_t key = with_uvs ? (std::uint64_t(vertex) << 32) | std::uint64_t(uv) : std::uint64_t(vertex);
            const auto [found, added] = builder.local_index.emplace(key, std::uint32_t(builder.mesh.positions.size()));
            if (added) {
                builder.mesh.positions.push_back(vertices_[std::size_t(vertex - 1)]);
                if (with_uvs) builder.mesh.uvs.push_back(texture_coordinates_[std::size_t(uv - 1)]);
            }
            return found->second;
        };
        for (std::size_t i = 0; i < indices.size(); i += 3)
            builder.mesh.triangles.push_back({local(indices[i]), local(indices[i + 1]), local(indices[i + 2])});
    }

    void add_ply_faces(scene::Mesh& mesh, const Element& faces, const std::string& ply_name) const {
        PlyMesh ply;
        try {
            ply = read_ply(reader_.folder() / ply_name);
        } catch (const LoadError& error) {
            // The PLY reader's message names the PLY file; this adds which scene element asked for it.
            throw LoadError(reader_.file(), faces.where(), error.what());
        } catch (const std::exception& error) {
            throw LoadError(reader_.file(), faces.where(), (reader_.folder() / ply_name).string() + ": " + error.what());
        }
        const std::size_t base = mesh.positions.size();
        for (const auto& triangle : ply.triangles)
            for (std::uint32_t index : triangle)
                if (index >= ply.positions.size())
                    reader_.fail(faces, (reader_.folder() / ply_name).string() + ": a face uses vertex " +
                                            std::to_string(index) + " of " + std::to_string(ply.positions.size()));
        // A mesh built from several Faces keeps normals or uvs only if every part has them;
        // finish_mesh drops partial ones.
        mesh.positions.insert(mesh.positions.end(), ply.positions.begin(), ply.positions.end());
        if (ply.normals.size() == ply.positions.size() && mesh.normals.size() == base)
            mesh.normals.insert(mesh.normals.end(), ply.normals.begin(), ply.normals.end());
        if (ply.uvs.size() == ply.positions.size() && mesh.uvs.size() == base)
            mesh.uvs.insert(mesh.uvs.end(), ply.uvs.begin(), ply.uvs.end());
        for (const auto& triangle : ply.triangles)
            mesh.triangles.push_back({std::uint32_t(triangle[0] + base), std::uint32_t(triangle[1] + base),
                                      std::uint32_t(triangle[2] + base)});
    }

    static void finish_mesh(scene::Mesh& mesh) {
        if (mesh.normals.size() != mesh.positions.size()) mesh.normals.clear();
        if (mesh.uvs.size() != mesh.positions.size()) mesh.uvs.clear();
    }

private:
    ElementReader& reader_;
    std::vector<scene::Vec3> vertices_;
    std::vector<scene::Vec2> texture_coordinates_;
};

}  // namespace prism::io::detail::scene_loader
