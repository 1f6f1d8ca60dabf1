// A scene made harder for floating point, in two ways the precision tests, the benchmarks and the
// speed-against-accuracy chart share: a mesh subdivided into tiny triangles (the tiny-triangle
// dragon is dragon_lowres's dragon subdivided three times), and the whole scene moved far from
// the origin. Both keep the image: the subdivided surface is the same surface, and the moved
// scene moves its camera and lights with it.
#pragma once

#include <prism/geometry/subdivide.hpp>
#include <prism/math/transform.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace prism::scene {

// Replaces the mesh with the most triangles by its midpoint subdivision, `levels` times (4^levels
// times the triangles), in world space: its transform is applied first, in double, and the
// subdivided mesh gets the identity. Subdivision makes no normals or texture coordinates, so the
// mesh keeps none. Returns the mesh's index.
inline std::size_t subdivide_largest_mesh(Scene& scene, int levels) {
    if (scene.meshes.empty()) throw std::invalid_argument("subdivide_largest_mesh: the scene has no mesh");
    const auto largest = std::max_element(scene.meshes.begin(), scene.meshes.end(), [](const Mesh& a, const Mesh& b) {
        return a.triangles.size() < b.triangles.size();
    });
    for (const MeshInstance& instance : scene.mesh_instances)
        if (instance.base_mesh == std::size_t(largest - scene.meshes.begin()))
            throw std::invalid_argument("subdivide_largest_mesh: the largest mesh is the base of instances");
    IndexedMesh<double> subdivided = subdivide_midpoint(world_space_mesh(*largest), levels);
    largest->transform = Mat4(1.0);
    largest->positions = std::move(subdivided.positions);
    largest->triangles = std::move(subdivided.triangles);
    largest->normals.clear();
    largest->uvs.clear();
    return std::size_t(largest - scene.meshes.begin());
}

// Moves every object, light and camera by `offset`.
// Geometry written in world space (an identity transform) is moved itself, so its coordinates,
// and a float renderer's copies of them, really lie near the offset: that is what makes a scene
// far from the origin hard. A transformed object gets the translation composed after its
// transform instead. A mesh that instances share keeps its positions, because an instance's
// transform maps the base mesh's own coordinates (scene.hpp); the instances are moved by their
// transforms. Directions (directional lights, gazes, motion) do not change.
inline void translate(Scene& scene, const Vec3& offset) {
    const Mat4 moved = prism::translation(offset);
    std::vector<bool> instanced(scene.meshes.size(), false);
    for (const MeshInstance& instance : scene.mesh_instances) instanced.at(instance.base_mesh) = true;

    for (std::size_t i = 0; i < scene.meshes.size(); ++i) {
        Mesh& mesh = scene.meshes[i];
        if (mesh.transform == Mat4(1.0) && !instanced[i]) {
            for (Vec3& position : mesh.positions) position += offset;
        } else {
            mesh.transform = moved * mesh.transform;
        }
    }
    for (MeshInstance& instance : scene.mesh_instances) instance.transform = moved * instance.transform;
    for (Sphere& sphere : scene.spheres) {
        if (sphere.transform == Mat4(1.0)) sphere.center += offset;
        else sphere.transform = moved * sphere.transform;
    }
    for (Plane& plane : scene.planes) {
        if (plane.transform == Mat4(1.0)) plane.point += offset;
        else plane.transform = moved * plane.transform;
    }

    for (Camera& camera : scene.cameras) camera.position += offset;
    for (PointLight& light : scene.point_lights) light.position += offset;
    for (SpotLight& light : scene.spot_lights) light.position += offset;
    for (AreaLight& light : scene.area_lights) light.corner += offset;
}

}  // namespace prism::scene
