// What a scene needs from a renderer, measured from the plain description: how small its
// triangles and spheres are against the magnitude of their coordinates (which decides float or
// double),
// and which light types it uses (which decides the compiled light set). "Model no more than a
// scene needs": the dispatcher instantiates the renderer these features call for, and says why.
#pragma once

#include <prism/scene/scene.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace prism::scene {

struct PrecisionFeatures {
    std::size_t triangles_measured = 0;
    // Edge length over the largest vertex coordinate magnitude, per triangle (world space): how
    // many units in the last place of its own coordinates a triangle spans. Float resolves
    // 2^-24 relative, so a triangle with relative size 2^-12 spans about 4096 float ulps.
    double relative_size_percentile_1 = std::numeric_limits<double>::infinity();
    double relative_size_minimum = std::numeric_limits<double>::infinity();
    double largest_coordinate = 0;  // world space, over every mesh vertex and sphere
    // The same for spheres: world radius over the magnitude of the farthest point, the smallest
    // over every sphere. A sphere far from the origin loses its shape in float just as a
    // triangle does, and the double-precision triangle test does nothing for it.
    std::size_t spheres_measured = 0;
    double sphere_relative_size_minimum = std::numeric_limits<double>::infinity();
};

namespace detail {

// Shortest edge over the largest coordinate magnitude of one triangle; zero-area triangles
// (repeated vertices) say nothing about precision and are skipped by returning infinity.
inline double relative_size(const Vec3& a, const Vec3& b, const Vec3& c, double& largest) {
    const double magnitude = std::max({glm::length(a), glm::length(b), glm::length(c)});
    largest = std::max(largest, magnitude);
    const double edge = std::min({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    if (!(edge > 0)) return std::numeric_limits<double>::infinity();
    return magnitude > 0 ? edge / magnitude : std::numeric_limits<double>::infinity();
}

// A sphere's smallest world radius (the shortest axis of the ellipsoid its transform makes, as
// the shortest image of the unit axes, which is what the radius shrinks to along that axis).
inline double world_radius(const Sphere& sphere) {
    const glm::dmat3 linear(sphere.transform);
    return sphere.radius * std::min({glm::length(linear[0]), glm::length(linear[1]), glm::length(linear[2])});
}

}  // namespace detail

// Measures at most `budget` triangles, spread evenly over every placed mesh (meshes and their
// instances, under their transforms), so a million-triangle scene costs milliseconds.
inline PrecisionFeatures measure_precision(const Scene& scene, std::size_t budget = 200000) {
    struct Placement {
        const Mesh* mesh;
        Mat4 transform;
    };
    std::vector<Placement> placements;
    for (const Mesh& mesh : scene.meshes) placements.push_back({&mesh, mesh.transform});
    for (const MeshInstance& instance : scene.mesh_instances)
        if (instance.base_mesh < scene.meshes.size())
            placements.push_back({&scene.meshes[instance.base_mesh], instance.transform});
    std::size_t total = 0;
    for (const Placement& placement : placements) total += placement.mesh->triangles.size();

    PrecisionFeatures features;
    for (const Sphere& sphere : scene.spheres) {
        const double radius = detail::world_radius(sphere);
        const double magnitude = glm::length(Vec3(sphere.transform * glm::dvec4(sphere.center, 1.0))) + radius;
        features.largest_coordinate = std::max(features.largest_coordinate, magnitude);
        if (!(radius > 0) || !(magnitude > 0)) continue;
        ++features.spheres_measured;
        features.sphere_relative_size_minimum = std::min(features.sphere_relative_size_minimum, radius / magnitude);
    }
    if (total == 0) return features;
    const std::size_t stride = std::max<std::size_t>(1, total / budget);
    std::vector<double> sizes;
    sizes.reserve(std::min(total, budget + placements.size()));
    for (const Placement& placement : placements) {
        const auto world = [&](std::uint32_t v) {
            return Vec3(placement.transform * glm::dvec4(placement.mesh->positions[v], 1.0));
        };
        const auto& triangles = placement.mesh->triangles;
        for (std::size_t i = 0; i < triangles.size(); i += stride) {
            const auto& t = triangles[i];
            const double size = detail::relative_size(world(t[0]), world(t[1]), world(t[2]), features.largest_coordinate);
            if (std::isfinite(size)) sizes.push_back(size);
        }
    }
    features.triangles_measured = sizes.size();
    if (sizes.empty()) return features;
    const auto percentile = sizes.begin() + std::ptrdiff_t(sizes.size() / 100);
    std::nth_element(sizes.begin(), percentile, sizes.end());
    features.relative_size_percentile_1 = *percentile;
    features.relative_size_minimum = *std::min_element(sizes.begin(), sizes.end());
    return features;
}

}  // namespace prism::scene
