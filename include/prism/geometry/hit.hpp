// The closest-hit record traversal fills, and the surface point shading derives from it once the
// closest hit is known (so traversal never computes normals or texture coordinates it discards).
#pragma once

#include <prism/math/vector.hpp>

#include <cstdint>
#include <span>

namespace prism {

template <Scalar Real>
struct Hit {
    Real t = infinity<Real>;
    std::uint32_t object = 0;     // index of the instance (or plane) hit
    // A triangle's position in its mesh's index order (TriangleMesh reorders triangles for
    // locality), not its position in scene::Mesh::triangles, except for a mesh that shares
    // SceneIndex's merged world-space index with others: it keeps the file's order. 0 for
    // spheres and planes.
    std::uint32_t primitive = 0;
    Real b1 = 0, b2 = 0;          // barycentrics for triangles
};

template <Scalar Real>
struct SurfacePoint {
    Vec3<Real> position{0};
    Vec3<Real> geometric_normal{0};  // unit, world space, as the surface is oriented (not flipped)
    Vec3<Real> shading_normal{0};    // unit; interpolated for smooth meshes
    Vec2<Real> uv{0};
    // World-space derivatives of the position along u and v (not unit): the tangent frame of
    // normal and bump maps. Zero where the surface has no (u, v): meshes without texture
    // coordinates, planes.
    Vec3<Real> dpdu{0}, dpdv{0};
    // The space solid textures (Perlin noise, checkerboards) are evaluated in and bump heights are
    // measured in: a mesh's object space, world space on spheres and planes, as the course does
    // (texture/texture_set.hpp has the evidence). texture_position is the point in that space;
    // texture_frame carries its directions to world space (the linear part of a mesh's
    // transformation, the identity elsewhere and for points built by hand).
    Vec3<Real> texture_position{0};
    Mat3<Real> texture_frame{1};
    Vec3<Real> local_position{0};  // in the object's own space (a sphere's (u, v) come from it)
    std::uint32_t material = 0;
    std::span<const std::uint32_t> textures;  // the object's textures (indices into Scene::textures)
    // What SceneSurfaces::spawn_origin needs to leave the surface by its error bound: the hit
    // point in object space with its error, the object-space geometric normal, the object, and
    // the instant of the ray that found it.
    Vec3<Real> object_point{0}, object_error{0}, object_normal{0, 0, 1};
    std::uint32_t object = 0;
    Real time = 0;
};

}  // namespace prism
