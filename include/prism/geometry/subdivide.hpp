// Midpoint (1 -> 4) subdivision of indexed triangle meshes, the icosphere, radial perturbation
// and the closedness check: the geometry of the stress scenes (`prism-stress`) and of the
// benchmarks' tiny-triangle dragon. A midpoint is made once per edge and shared by the two
// triangles that meet there, so a closed (watertight) mesh stays closed.
#pragma once

#include <prism/math/vector.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace prism {

// Positions and triangles (indices into positions) and nothing else.
template <Scalar Real>
struct IndexedMesh {
    std::vector<Vec3<Real>> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
};

struct SubdivisionOptions {
    // Each new midpoint moves along the surface normal at its edge by u * perturb * (edge
    // length), u uniform in [-1, 1]: relative to the edge so that the same value perturbs a
    // mesh alike at every scale. 0 keeps every vertex on the original triangles.
    double perturb = 0.0;
    std::uint64_t seed = 1;
};

namespace detail::subdivide {

// SplitMix64 (Steele, Lea, Flood 2014): a tiny generator whose output is the same on every
// platform, unlike the standard distributions, so a seed names one mesh everywhere.
struct SplitMix64 {
    std::uint64_t state;
    std::uint64_t next() {
        std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    double uniform_signed() { return double(next() >> 11) * 0x1.0p-52 - 1.0; }  // in [-1, 1)
};

inline std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
    return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
}

template <Scalar Real>
IndexedMesh<Real> subdivide_once(const IndexedMesh<Real>& mesh, const SubdivisionOptions& options,
                                 std::uint64_t level_seed) {
    const std::size_t triangle_count = mesh.triangles.size();
    if (triangle_count > std::numeric_limits<std::uint32_t>::max() / 4)
        throw std::length_error("subdivision: " + std::to_string(4 * triangle_count) +
                                " triangles do not fit 32-bit indices");
    // Pass 1: one midpoint index per edge, in the order the triangles first reach the edges,
    // and the area-weighted normal of the faces that share the edge (for the perturbation).
    std::unordered_map<std::uint64_t, std::uint32_t> midpoint_of;
    midpoint_of.reserve(triangle_count * 2);
    std::vector<std::array<std::uint32_t, 2>> edges;  // the two ends of each new midpoint
    std::vector<glm::dvec3> edge_normals;
    edges.reserve(triangle_count * 3 / 2 + 3);
    const std::size_t first_new = mesh.positions.size();
    std::vector<std::array<std::uint32_t, 3>> corner_midpoints(triangle_count);
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const auto& tri = mesh.triangles[t];
        const glm::dvec3 p0(mesh.positions[tri[0]]), p1(mesh.positions[tri[1]]), p2(mesh.positions[tri[2]]);
        const glm::dvec3 face_normal = glm::cross(p1 - p0, p2 - p0);
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
            const auto [found, added] =
                midpoint_of.try_emplace(edge_key(a, b), std::uint32_t(first_new + edges.size()));
            if (added) {
                if (found->second == std::numeric_limits<std::uint32_t>::max())
                    throw std::length_error("subdivision: too many vertices for 32-bit indices");
                edges.push_back({a, b});
                edge_normals.push_back(face_normal);
            } else {
                edge_normals[found->second - first_new] += face_normal;
            }
            corner_midpoints[t][k] = found->second;
        }
    }

    // Pass 2: positions. Midpoints are formed in double, where the midpoint of two floats is
    // exact, and rounded once to Real.
    IndexedMesh<Real> result;
    result.positions.reserve(first_new + edges.size());
    result.positions = mesh.positions;
    SplitMix64 random{options.seed * 0x2545F4914F6CDD1Dull + level_seed};
    for (std::size_t e = 0; e < edges.size(); ++e) {
        const glm::dvec3 a(mesh.positions[edges[e][0]]), b(mesh.positions[edges[e][1]]);
        glm::dvec3 midpoint = (a + b) * 0.5;
        if (options.perturb != 0.0) {
            const double u = random.uniform_signed();
            const double normal_length = glm::length(edge_normals[e]);
            if (normal_length > 0)
                midpoint += (u * options.perturb * glm::length(b - a) / normal_length) * edge_normals[e];
        }
        result.positions.push_back(Vec3<Real>(midpoint));
    }

    // Pass 3: the four children of triangle t are triangles 4t .. 4t+3, wound as their parent.
    result.triangles.reserve(4 * triangle_count);
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const auto& [a, b, c] = mesh.triangles[t];
        const auto& [ab, bc, ca] = corner_midpoints[t];
        result.triangles.push_back({a, ab, ca});
        result.triangles.push_back({ab, b, bc});
        result.triangles.push_back({ca, bc, c});
        result.triangles.push_back({ab, bc, ca});
    }
    return result;
}

}  // namespace detail::subdivide

// Splits every triangle into four at its edge midpoints, `levels` times: 4^levels times the
// triangles, the same surface (unless options.perturb is set). After the call, the
// descendants of input triangle t are triangles [t * 4^levels, (t + 1) * 4^levels).
template <Scalar Real>
IndexedMesh<Real> subdivide_midpoint(IndexedMesh<Real> mesh, int levels, const SubdivisionOptions& options = {}) {
    if (levels < 0) throw std::invalid_argument("subdivision: the number of levels must not be negative");
    for (int level = 0; level < levels; ++level)
        mesh = detail::subdivide::subdivide_once(mesh, options, std::uint64_t(level));
    return mesh;
}

// The icosahedron subdivided `subdivisions` times with every vertex on the unit sphere around
// the origin: 20 * 4^subdivisions triangles, wound counter-clockwise seen from outside, closed.
template <Scalar Real>
IndexedMesh<Real> icosphere(int subdivisions) {
    const double g = (1.0 + std::sqrt(5.0)) / 2.0;  // the golden ratio
    IndexedMesh<double> mesh;
    mesh.positions = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                      {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                      {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    for (auto& p : mesh.positions) p = glm::normalize(p);
    for (int level = 0; level < subdivisions; ++level) {
        mesh = subdivide_midpoint(std::move(mesh), 1);
        for (auto& p : mesh.positions) p = glm::normalize(p);
    }
    IndexedMesh<Real> result;
    result.triangles = std::move(mesh.triangles);
    result.positions.reserve(mesh.positions.size());
    for (const auto& p : mesh.positions) result.positions.push_back(Vec3<Real>(p));
    return result;
}

// Moves every vertex along the ray from `center` through it by a factor 1 + amplitude * u,
// u uniform in [-1, 1], seeded: a bumpy surface that stays closed since vertices are shared.
template <Scalar Real>
void perturb_radially(IndexedMesh<Real>& mesh, const Vec3<Real>& center, double amplitude, std::uint64_t seed) {
    if (!(amplitude >= 0.0 && amplitude < 1.0))
        throw std::invalid_argument("radial perturbation: the amplitude must lie in [0, 1)");
    detail::subdivide::SplitMix64 random{seed};
    const glm::dvec3 c(center);
    for (auto& p : mesh.positions) {
        const double factor = 1.0 + amplitude * random.uniform_signed();
        p = Vec3<Real>(c + (glm::dvec3(p) - c) * factor);
    }
}

// Whether the triangles form closed, consistently oriented surfaces: every edge is shared by
// exactly two triangles that run along it in opposite directions (and no triangle repeats a
// vertex). This is what "watertight" means for a ray test with shared vertices.
inline bool is_closed(std::span<const std::array<std::uint32_t, 3>> triangles) {
    std::vector<std::uint64_t> directed;
    directed.reserve(triangles.size() * 3);
    for (const auto& tri : triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
            if (a == b) return false;
            directed.push_back((std::uint64_t(a) << 32) | b);
        }
    std::sort(directed.begin(), directed.end());
    if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
    for (const std::uint64_t edge : directed) {
        const std::uint64_t reverse = (edge << 32) | (edge >> 32);
        if (!std::binary_search(directed.begin(), directed.end(), reverse)) return false;
    }
    return true;
}

// A scene mesh's triangles in world space (its transform applied), in double.
inline IndexedMesh<double> world_space_mesh(const scene::Mesh& mesh) {
    IndexedMesh<double> result;
    result.triangles = mesh.triangles;
    result.positions.reserve(mesh.positions.size());
    for (const auto& p : mesh.positions) result.positions.push_back(glm::dvec3(mesh.transform * glm::dvec4(p, 1.0)));
    return result;
}

}  // namespace prism
