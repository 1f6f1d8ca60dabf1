// The <Objects> section of a scene file: Mesh, Triangle (a mesh of one face), Sphere, Plane, the
// object lights LightMesh and LightSphere (with a <Radiance>), and MeshInstance, which carries its
// whole transform (its own, after the base mesh's unless resetTransform="true"), its material and
// textures (its own, else the base's) and its own MotionBlur only; a baseMeshId may name another
// instance. MotionBlur on Mesh, Triangle, Sphere and MeshInstance.
#pragma once

#include <prism/io/element.hpp>
#include <prism/io/element_reader.hpp>
#include <prism/io/limits.hpp>
#include <prism/io/material_loader.hpp>
#include <prism/io/texture_loader.hpp>
#include <prism/io/transformation_loader.hpp>
#include <prism/io/vertex_data_loader.hpp>
#include <prism/scene/scene.hpp>

#include <glm/glm.hpp>

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace prism::io::detail::scene_loader {

class ObjectLoader {
public:
    ObjectLoader(ElementReader& reader, scene::Scene& scene, const ResourceLimits& limits, MemoryUse& memory,
                 const TransformationLoader& transformations, const MaterialLoader& materials, const TextureLoader& textures,
                 VertexDataLoader& vertex_data)
        : reader_(reader), scene_(scene), limits_(limits), memory_(memory), transformations_(transformations),
          materials_(materials), textures_(textures), vertex_data_(vertex_data) {}

    void read(const Element& section) {
        std::vector<const Element*> instances;
        for (const Element& element : section.children) {
            if (element.name == "Mesh") read_mesh(element);
            else if (element.name == "Triangle") read_triangle(element);
            else if (element.name == "Sphere") read_sphere(element);
            else if (element.name == "LightMesh") read_mesh(element, true);
            else if (element.name == "LightSphere") read_sphere(element, true);
            else if (element.name == "Plane") read_plane(element);
            else if (element.name == "MeshInstance") instances.push_back(&element);
            else reader_.note_unsupported(element);
        }
        // After every mesh, since an instance may name a mesh written after it.
        read_instances(instances);
    }

private:
    // What every object but an instance has: an id, a <Material> and <Transformations>.
    template <class Object>
    void read_id_material_transform(const Element& element, Object& object) const {
        object.id = reader_.id_of(element);
        object.material = materials_.material_of(reader_.required(element, "Material"));
        object.transform = transformations_.transformation_of(element);
    }

    // <MotionBlur>x y z</MotionBlur>: the world-space translation over the shutter interval.
    scene::Vec3 motion_of(const Element& object) const {
        const Element* motion = object.child("MotionBlur");
        return motion != nullptr ? reader_.vector3(*motion) : scene::Vec3(0.0);
    }

    scene::ShadingMode shading_of(const Element& element) const {
        const std::string* mode = element.attribute("shadingMode");
        if (mode == nullptr || trim(*mode) == "flat") return scene::ShadingMode::flat;
        if (trim(*mode) == "smooth") return scene::ShadingMode::smooth;
        reader_.fail(element, "shadingMode must be \"flat\" or \"smooth\", not " + in_quotes(*mode));
    }

    // A <LightMesh> is a Mesh with a <Radiance> (emitting = true).
    void read_mesh(const Element& element, bool emitting = false) {
        scene::Mesh mesh;
        mesh.shading = shading_of(element);
        read_id_material_transform(element, mesh);
        VertexDataLoader::MeshBuilder builder{mesh};
        bool has_faces = false;
        for (const Element& faces : element.children) {
            if (faces.name != "Faces") continue;
            has_faces = true;
            if (const std::string* type = faces.attribute("type"); type != nullptr && trim(*type) != "triangle")
                reader_.fail(faces, "unsupported face type " + in_quotes(*type) + " (expected \"triangle\")");
            if (const std::string* ply = faces.attribute("plyFile")) {
                vertex_data_.add_ply_faces(mesh, faces, std::string(trim(*ply)));
            } else {
                // Binary face indices mean what inline ones do: 1-based, shifted by vertexOffset.
                const std::vector<long long> indices =
                    faces.attribute("binaryFile") != nullptr
                        ? vertex_data_.read_binary_file(
                              faces, [](const auto& path) { return read_binary_integers(path, 3, "faces"); })
                        : reader_.integers(faces);
                vertex_data_.add_indexed_faces(builder, faces, indices, reader_.integer_attribute(faces, "vertexOffset", 0),
                                               reader_.integer_attribute(faces, "textureOffset", 0));
            }
        }
        if (!has_faces) reader_.fail(element, "missing <Faces>");
        count_triangles(element, mesh.triangles.size());
        vertex_data_.finish_mesh(mesh);
        mesh.textures = textures_.textures_of(element);
        mesh.motion = motion_of(element);
        if (emitting) mesh.radiance = radiance_of(element);
        reader_.note_unsupported_children(element, {"Material", "Transformations", "Faces", "Textures", "Texture",
                                                    "MotionBlur", emitting ? "Radiance" : "Faces"});
        if (!mesh_indices_.emplace(mesh.id, scene_.meshes.size()).second) ambiguous_mesh_ids_.insert(mesh.id);
        scene_.meshes.push_back(std::move(mesh));
    }

    // A Triangle is a mesh of one face.
    void read_triangle(const Element& element) {
        scene::Mesh mesh;
        mesh.shading = shading_of(element);
        read_id_material_transform(element, mesh);
        const Element& indices = reader_.required(element, "Indices");
        const std::vector<long long> corners = reader_.integers(indices);
        if (corners.size() != 3) reader_.fail(indices, "expected 3 vertex indices, found " + std::to_string(corners.size()));
        VertexDataLoader::MeshBuilder builder{mesh};
        vertex_data_.add_indexed_faces(builder, indices, corners, 0, 0);
        count_triangles(element, 1);
        vertex_data_.finish_mesh(mesh);
        mesh.textures = textures_.textures_of(element);
        mesh.motion = motion_of(element);
        reader_.note_unsupported_children(element,
                                          {"Material", "Transformations", "Indices", "Textures", "Texture", "MotionBlur"});
        scene_.meshes.push_back(std::move(mesh));
    }

    // The scene's triangles so far, with its textures and films, against the memory rendering them
    // will take (limits.hpp).
    void count_triangles(const Element& element, std::size_t added) {
        memory_.triangles += added;
        if (memory_.over(limits_.memory_bytes))
            reader_.fail(element, "the scene's meshes reach " + std::to_string(memory_.triangles) + " triangles here: " +
                                      memory_.over_message(limits_.memory_bytes));
    }

    // A <LightSphere> is a Sphere with a <Radiance> (emitting = true).
    void read_sphere(const Element& element, bool emitting = false) {
        scene::Sphere sphere;
        read_id_material_transform(element, sphere);
        sphere.center = vertex_data_.vertex_of(reader_.required(element, "Center"));
        const Element& radius = reader_.required(element, "Radius");
        sphere.radius = reader_.number(radius);
        if (!(sphere.radius > 0.0)) reader_.fail(radius, "the radius must be positive");
        sphere.textures = textures_.textures_of(element);
        sphere.motion = motion_of(element);
        if (emitting) sphere.radiance = radiance_of(element);
        reader_.note_unsupported_children(element, {"Material", "Transformations", "Center", "Radius", "Textures", "Texture",
                                                    "MotionBlur", emitting ? "Radiance" : "Center"});
        scene_.spheres.push_back(std::move(sphere));
    }

    // An object light's <Radiance>: three non-negative numbers.
    scene::Vec3 radiance_of(const Element& element) {
        const Element& radiance = reader_.required(element, "Radiance");
        const scene::Vec3 value = reader_.vector3(radiance);
        if (glm::any(glm::lessThan(value, scene::Vec3(0.0)))) reader_.fail(radiance, "the radiance must not be negative");
        return value;
    }

    void read_plane(const Element& element) {
        scene::Plane plane;
        read_id_material_transform(element, plane);
        plane.point = vertex_data_.vertex_of(reader_.required(element, "Point"));
        const Element& normal = reader_.required(element, "Normal");
        plane.normal = reader_.vector3(normal);
        if (glm::length(plane.normal) == 0.0) reader_.fail(normal, "the normal is zero");
        plane.textures = textures_.textures_of(element);
        reader_.note_unsupported_children(element,
                                          {"Material", "Transformations", "Point", "Normal", "Textures", "Texture"});
        scene_.planes.push_back(std::move(plane));
    }

    void read_instances(const std::vector<const Element*>& elements) {
        enum class State { waiting, resolving, done };
        std::vector<State> state(elements.size(), State::waiting);
        std::vector<scene::MeshInstance> instances(elements.size());
        std::map<std::string, std::size_t> instance_indices;
        std::set<std::string> ambiguous_instance_ids;
        for (std::size_t i = 0; i < elements.size(); ++i)
            if (!instance_indices.emplace(reader_.id_of(*elements[i]), i).second)
                ambiguous_instance_ids.insert(reader_.id_of(*elements[i]));

        // baseMeshId names a Mesh; should it name another MeshInstance, the instance resolves to
        // that instance's mesh, after that instance's transform. base_instance finds which.
        const auto base_instance = [&](std::size_t i) -> std::optional<std::size_t> {
            const Element& element = *elements[i];
            const std::string base_id(trim(reader_.required_attribute(element, "baseMeshId")));
            if (mesh_indices_.count(base_id) != 0) {
                if (ambiguous_mesh_ids_.count(base_id) != 0)
                    reader_.fail(element, "baseMeshId " + in_quotes(base_id) + " is ambiguous: several meshes have this id");
                return std::nullopt;
            }
            const auto other = instance_indices.find(base_id);
            if (other == instance_indices.end())
                reader_.fail(element, "unknown baseMeshId " + in_quotes(base_id) + ": no <Mesh> has this id");
            if (ambiguous_instance_ids.count(base_id) != 0)
                reader_.fail(element, "baseMeshId " + in_quotes(base_id) + " is ambiguous: several instances have this id");
            return other->second;
        };
        // Resolves instance i, whose base (if an instance) is done.
        const auto resolve = [&](std::size_t i) {
            const Element& element = *elements[i];
            scene::MeshInstance& instance = instances[i];
            instance.id = reader_.id_of(element);
            glm::dmat4 base_transform(1.0);
            std::size_t base_material = 0;
            std::vector<std::size_t> base_textures;
            if (const std::optional<std::size_t> other = base_instance(i)) {
                instance.base_mesh = instances[*other].base_mesh;
                base_transform = instances[*other].transform;
                base_material = instances[*other].material;
                base_textures = instances[*other].textures;
            } else {
                instance.base_mesh = mesh_indices_.at(std::string(trim(*element.attribute("baseMeshId"))));
                base_transform = scene_.meshes[instance.base_mesh].transform;
                base_material = scene_.meshes[instance.base_mesh].material;
                base_textures = scene_.meshes[instance.base_mesh].textures;
            }
            const glm::dmat4 own = transformations_.transformation_of(element);
            instance.transform = reader_.boolean_attribute(element, "resetTransform", false) ? own : own * base_transform;
            const Element* material = element.child("Material");
            instance.material = material != nullptr ? materials_.material_of(*material) : base_material;
            // Textures follow the material: the instance's own, else its base's. Motion is the
            // instance's own only (no course file moves an instance; a base mesh's MotionBlur
            // moves that mesh, not its copies).
            const bool own_textures = element.child("Textures") != nullptr || element.child("Texture") != nullptr;
            instance.textures = own_textures ? textures_.textures_of(element) : base_textures;
            instance.motion = motion_of(element);
            reader_.note_unsupported_children(element, {"Material", "Transformations", "Textures", "Texture", "MotionBlur"});
            state[i] = State::done;
        };
        // A chain of instances is followed down to its mesh on a list, then resolved from the mesh
        // up: a loop, not recursion, so no chain in a file can overflow the stack.
        for (std::size_t i = 0; i < elements.size(); ++i) {
            std::vector<std::size_t> chain;
            for (std::optional<std::size_t> k = i; k && state[*k] != State::done; k = base_instance(*k)) {
                if (state[*k] == State::resolving)
                    reader_.fail(*elements[*k], "the instances' baseMeshId references form a cycle");
                state[*k] = State::resolving;
                chain.push_back(*k);
            }
            for (auto k = chain.rbegin(); k != chain.rend(); ++k) resolve(*k);
        }
        for (scene::MeshInstance& instance : instances) scene_.mesh_instances.push_back(std::move(instance));
    }

    ElementReader& reader_;
    scene::Scene& scene_;
    const ResourceLimits& limits_;
    MemoryUse& memory_;  // shared with the texture and camera loaders
    const TransformationLoader& transformations_;
    const MaterialLoader& materials_;
    const TextureLoader& textures_;
    VertexDataLoader& vertex_data_;
    std::map<std::string, std::size_t> mesh_indices_;     // ids of Mesh elements only
    std::set<std::string> ambiguous_mesh_ids_;
};

}  // namespace prism::io::detail::scene_loader
