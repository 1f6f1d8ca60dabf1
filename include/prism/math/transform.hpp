// 4x4 affine transforms as the course's scene files write them (Translation, Scaling, Rotation
// by an angle in degrees about an axis, Composite given row-major), built in double precision,
// and the three ways to apply one: to points, to directions, and to normals (inverse transpose).
// Matrices are GLM's: column-major storage, applied to column vectors (p' = M p), so "first A,
// then B" is the product B * A.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/math/vector.hpp>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <array>

namespace prism {

inline glm::dmat4 translation(const glm::dvec3& offset) { return glm::translate(glm::dmat4(1.0), offset); }

inline glm::dmat4 scaling(const glm::dvec3& factors) { return glm::scale(glm::dmat4(1.0), factors); }

// Counter-clockwise about `axis` (right-handed) by `angle_degrees`; the axis need not be unit
// length but must not be zero.
inline glm::dmat4 rotation(double angle_degrees, const glm::dvec3& axis) {
    return glm::rotate(glm::dmat4(1.0), glm::radians(angle_degrees), glm::normalize(axis));
}

// The course writes a Composite's 16 numbers row by row; GLM indexes matrix[column][row].
inline glm::dmat4 composite_from_row_major(const std::array<double, 16>& rows) {
    glm::dmat4 matrix(1.0);
    for (int row = 0; row < 4; ++row)
        for (int column = 0; column < 4; ++column) matrix[column][row] = rows[std::size_t(row * 4 + column)];
    return matrix;
}

// The transforms are affine, so the homogeneous coordinate stays 1 and needs no division.
// Each coordinate is summed as (m0 x + m1 y) + (m2 z + t): GLM's order for matrix * vec4(p, 1)
// (its m3 * 1 is exact), so the bits are GLM's, and pbrt's order, whose gamma(3) rounding bound
// geometry/surface_error.hpp relies on. Written out rather than through GLM so that it inlines:
// GCC left GLM's product out of line on the spawn and hit-point paths of instanced scenes.
template <Scalar Real>
PRISM_FORCE_INLINE inline Vec3<Real> transform_point(const Mat4<Real>& matrix, const Vec3<Real>& point) {
    Vec3<Real> result;
    for (int row = 0; row < 3; ++row)
        result[row] = (matrix[0][row] * point.x + matrix[1][row] * point.y) + (matrix[2][row] * point.z + matrix[3][row]);
    return result;
}

// A 3x3 matrix applied to a vector, summed as (m0 x + m1 y) + m2 z: GLM's order and bits,
// written out to inline for the same reason as transform_point.
template <Scalar Real>
PRISM_FORCE_INLINE inline Vec3<Real> transform_direction(const Mat3<Real>& matrix, const Vec3<Real>& direction) {
    Vec3<Real> result;
    for (int row = 0; row < 3; ++row)
        result[row] = matrix[0][row] * direction.x + matrix[1][row] * direction.y + matrix[2][row] * direction.z;
    return result;
}

// Directions (gaze, up, ray directions, tangents) ignore the translation. Not renormalised: a
// ray direction scaled with the object keeps its parameter t meaning the same distance.
template <Scalar Real>
PRISM_FORCE_INLINE inline Vec3<Real> transform_direction(const Mat4<Real>& matrix, const Vec3<Real>& direction) {
    return transform_direction(Mat3<Real>(matrix), direction);
}

// The inverse transpose of the upper 3x3: it keeps normals perpendicular to transformed tangents
// under non-uniform scaling. Compute it once per object and apply it with transform_normal.
template <Scalar Real>
Mat3<Real> normal_matrix(const Mat4<Real>& matrix) {
    return glm::transpose(glm::inverse(Mat3<Real>(matrix)));
}

// Not renormalised, as the caller usually normalises after interpolation anyway.
template <Scalar Real>
PRISM_FORCE_INLINE inline Vec3<Real> transform_normal(const Mat3<Real>& inverse_transpose, const Vec3<Real>& normal) {
    return transform_direction(inverse_transpose, normal);
}

// For one normal: inverts the matrix on every call.
template <Scalar Real>
Vec3<Real> transform_normal(const Mat4<Real>& matrix, const Vec3<Real>& normal) {
    return normal_matrix(matrix) * normal;
}

}  // namespace prism
