// What a hit on a triangle mesh means: its normals (flat, or interpolated from the vertices for
// smooth shading), texture coordinates and tangents, and the hit point with the error bound a
// leaving ray must clear. Shared by every object that places the mesh. Its triangles are kept in
// the order hits name them (Hit::primitive): the slot order of the index that finds them, or
// the file's for an index that names a mesh's triangles as the file does (a merged world-space
// index, Embree). The index itself is TriangleMesh (geometry/triangle_mesh.hpp).
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/surface_error.hpp>
#include <prism/geometry/triangle_hit.hpp>
#include <prism/memory/huge_page_allocator.hpp>
#include <prism/parallel/for_each_run.hpp>
#include <prism/scene/scene.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace prism {

template <Scalar Real, class Intersector>
class MeshSurface {
public:
    using Storage = typename Intersector::template Storage<Real>;
    using Prepared = typename Intersector::template Prepared<Real>;

    // `order`: triangle slot -> the file's triangle, as the index lays them out (an index may
    // repeat triangles to pad its leaves); empty: the file's own order.
    MeshSurface(const scene::Mesh& mesh, std::span<const std::uint32_t> order)
        : smooth_(mesh.shading == scene::ShadingMode::smooth), triangle_count_(mesh.triangles.size()) {
        const std::size_t slots = order.empty() ? mesh.triangles.size() : order.size();
        // Resized without clearing (a HugePageVector) and written slot by slot: large meshes
        // copy theirs in parallel.
        triangles_.resize(slots);
        faces_.resize(slots);
        normals_.resize(slots);
        const auto copy = [&](std::size_t first, std::size_t end) {
            for (std::size_t slot = first; slot < end; ++slot) {
                const auto& face = mesh.triangles[order.empty() ? slot : order[slot]];
                faces_[slot] = face;
                const std::array<Vec3<Storage>, 3> p = {Vec3<Storage>(mesh.positions[face[0]]),
                                                        Vec3<Storage>(mesh.positions[face[1]]),
                                                        Vec3<Storage>(mesh.positions[face[2]])};
                triangles_[slot] = p;
                normals_[slot] = geometric_normal_of(p);
            }
        };
        constexpr std::size_t grain = 16384;  // slots per task
        for_each_run(slots, grain, copy);
        if (mesh.radiance != glm::dvec3(0.0) && !order.empty()) file_triangles_.assign(order.begin(), order.end());
        if (smooth_) vertex_normals_ = smooth_normals(mesh);
        for (const auto& uv : mesh.uvs) uvs_.emplace_back(uv);
    }

    std::size_t triangle_count() const { return triangle_count_; }
    bool smooth() const { return smooth_; }  // shadingMode="smooth": normals interpolated from the vertices

    // The hit point computed from the barycentrics, with the error bound a leaving ray must
    // clear (geometry/surface_error.hpp), in object space and the precision the triangle is
    // stored in.
    PRISM_FORCE_INLINE PointWithError<Real> spawn_point(const Hit<Real>& hit) const {
        const auto& p = triangles_[hit.primitive];
        return triangle_spawn_point<Real>(p[0], p[1], p[2], hit.b1, hit.b2);
    }

    // Normals, texture coordinates and the (u, v) tangent frame at a hit, in object space.
    void surface(const Hit<Real>& hit, Vec3<Real>& geometric_normal, Vec3<Real>& shading_normal, Vec2<Real>& uv,
                 Vec3<Real>& dpdu, Vec3<Real>& dpdv) const {
        geometric_normal = normals_[hit.primitive];
        const Real b0 = Real(1) - hit.b1 - hit.b2;
        const auto& face = faces_[hit.primitive];
        shading_normal = geometric_normal;
        if (smooth_) {
            const Vec3<Real> n = b0 * vertex_normals_[face[0]] + hit.b1 * vertex_normals_[face[1]] +
                                 hit.b2 * vertex_normals_[face[2]];
            const Real length = glm::length(n);
            if (length > 0) shading_normal = n / length;
        }
        if (uvs_.empty()) return;
        const Vec2<Real> uv0 = uvs_[face[0]], uv1 = uvs_[face[1]], uv2 = uvs_[face[2]];
        uv = b0 * uv0 + hit.b1 * uv1 + hit.b2 * uv2;
        // Solve [e1 e2] = [dpdu dpdv] [duv1 duv2] for the tangents (pbrt-v4 6.5.3); a
        // degenerate (u, v) mapping leaves them zero and the textures then keep the normal.
        const Vec2<Real> duv1 = uv1 - uv0, duv2 = uv2 - uv0;
        const Real determinant = duv1.x * duv2.y - duv1.y * duv2.x;
        if (std::abs(determinant) < std::numeric_limits<Real>::min()) return;
        const auto& p = triangles_[hit.primitive];
        const Vec3<Real> e1 = Vec3<Real>(p[1] - p[0]), e2 = Vec3<Real>(p[2] - p[0]);
        dpdu = (duv2.y * e1 - duv1.y * e2) / determinant;
        dpdv = (duv1.x * e2 - duv2.x * e1) / determinant;
    }

    // The triangle in `slot` alone, with the index's test and the hit record it writes: for an
    // index from outside (accel/embree.hpp) that finds the triangle and leaves prism to compute
    // the hit.
    bool intersect_triangle(std::uint32_t slot, const Ray<Real>& ray, Real& t_max, Hit<Real>& hit) const {
        const auto& p = triangles_[slot];
        TriangleHit<Real> triangle_hit;
        if (!Intersector::intersect(Prepared(ray), p[0], p[1], p[2], ray.t_min, t_max, triangle_hit)) return false;
        t_max = triangle_hit.t;
        hit.t = triangle_hit.t;
        hit.primitive = slot;
        hit.b1 = triangle_hit.b1;
        hit.b2 = triangle_hit.b2;
        return true;
    }

    // The file's number of the triangle in `slot`, for a mesh that emits (its LightMesh keeps
    // the file's order); other meshes keep no table, and get `slot` back.
    std::uint32_t file_triangle(std::uint32_t slot) const {
        return slot < file_triangles_.size() ? file_triangles_[slot] : slot;
    }

    // Whether culling skips the triangle in `slot` for a ray of this direction (object space):
    // the test the index's culled traversal makes.
    bool faces_away(std::uint32_t slot, const Vec3<Real>& direction) const {
        const auto& p = triangles_[slot];
        return glm::dot(Vec3<Real>(glm::cross(p[1] - p[0], p[2] - p[0])), direction) > 0;
    }

private:
    // Vertex normals as the course's renderer computes them: the normalised sum of the faces'
    // unnormalised normals, i.e. weighted by face area (with unit face normals instead,
    // low_poly_smooth drops from 58 to 30 dB against the course's image). A PLY file's own
    // normals take precedence.
    static std::vector<Vec3<Real>> smooth_normals(const scene::Mesh& mesh) {
        std::vector<Vec3<Real>> result(mesh.positions.size(), Vec3<Real>(0));
        if (mesh.normals.size() == mesh.positions.size()) {
            for (std::size_t i = 0; i < mesh.normals.size(); ++i) result[i] = Vec3<Real>(glm::normalize(mesh.normals[i]));
            return result;
        }
        std::vector<glm::dvec3> sums(mesh.positions.size(), glm::dvec3(0.0));
        for (const auto& face : mesh.triangles) {
            const glm::dvec3 area_weighted = glm::cross(mesh.positions[face[1]] - mesh.positions[face[0]],
                                                        mesh.positions[face[2]] - mesh.positions[face[0]]);
            for (std::uint32_t v : face) sums[v] += area_weighted;
        }
        for (std::size_t i = 0; i < sums.size(); ++i) {
            const double length = glm::length(sums[i]);
            if (length > 0) result[i] = Vec3<Real>(sums[i] / length);
        }
        return result;
    }

    // The unit geometric normal of a triangle as surface() reports it: its edges' cross product
    // in the stored precision, normalised in Real.
    static Vec3<Real> geometric_normal_of(const std::array<Vec3<Storage>, 3>& p) {
        return glm::normalize(Vec3<Real>(glm::cross(p[1] - p[0], p[2] - p[0])));
    }

    bool smooth_ = false;
    std::size_t triangle_count_ = 0;
    // In slot order.
    HugePageVector<std::array<Vec3<Storage>, 3>> triangles_;
    // Each slot's geometric_normal_of, worked out once: the square root and division of the
    // normalisation were half of surface()'s samples on hw7 path_diffuse (perf), for every
    // hit. 12 bytes a triangle (24 in double) beside the 48 of its vertices and indices.
    HugePageVector<Vec3<Real>> normals_;
    std::vector<std::array<std::uint32_t, 3>> faces_;  // vertex indices
    std::vector<std::uint32_t> file_triangles_;        // slot -> the file's triangle, for emitters
    std::vector<Vec3<Real>> vertex_normals_;
    std::vector<Vec2<Real>> uvs_;
};

}  // namespace prism
