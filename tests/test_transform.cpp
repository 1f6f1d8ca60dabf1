// The transform helpers against hand-computed values, for float and double alike.
#include <prism/math/transform.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>

namespace {

template <class Real>
Real tolerance() {
    return Real(std::is_same_v<Real, float> ? 1e-5 : 1e-12);
}

template <class Real>
std::string text(const prism::Vec3<Real>& v) {
    std::ostringstream out;
    out.precision(17);
    out << "(" << v.x << ", " << v.y << ", " << v.z << ")";
    return out.str();
}

// Equal within `tolerance` relative to the larger of 1 and the vectors' size.
template <class Real>
bool near(const prism::Vec3<Real>& a, const prism::Vec3<Real>& b, Real scale = Real(1)) {
    const Real size = std::max({scale, std::abs(b.x), std::abs(b.y), std::abs(b.z)});
    return std::abs(a.x - b.x) <= tolerance<Real>() * size && std::abs(a.y - b.y) <= tolerance<Real>() * size &&
           std::abs(a.z - b.z) <= tolerance<Real>() * size;
}

#define CHECK_NEAR(a, b) CHECK_MESSAGE(near(a, b), text(a) << " != " << text(b))

template <class Real>
prism::Mat4<Real> in(const glm::dmat4& matrix) {
    return prism::Mat4<Real>(matrix);
}

}  // namespace

TEST_CASE_TEMPLATE("translation moves points but not directions or normals", Real, float, double) {
    using V = prism::Vec3<Real>;
    const auto m = in<Real>(prism::translation({1.0, -2.0, 3.5}));
    CHECK_NEAR(prism::transform_point(m, V(1, 1, 1)), V(2, -1, 4.5));
    CHECK_NEAR(prism::transform_direction(m, V(1, 1, 1)), V(1, 1, 1));
    CHECK_NEAR(prism::transform_normal(m, V(0, 0, 1)), V(0, 0, 1));
}

TEST_CASE_TEMPLATE("scaling multiplies each axis", Real, float, double) {
    using V = prism::Vec3<Real>;
    const auto m = in<Real>(prism::scaling({2.0, 3.0, 0.5}));
    CHECK_NEAR(prism::transform_point(m, V(1, -1, 4)), V(2, -3, 2));
    CHECK_NEAR(prism::transform_direction(m, V(1, 1, 1)), V(2, 3, 0.5));
}

TEST_CASE_TEMPLATE("rotation is counter-clockwise about its axis, in degrees", Real, float, double) {
    using V = prism::Vec3<Real>;
    CHECK_NEAR(prism::transform_direction(in<Real>(prism::rotation(90.0, {0, 0, 1})), V(1, 0, 0)), V(0, 1, 0));
    CHECK_NEAR(prism::transform_direction(in<Real>(prism::rotation(90.0, {1, 0, 0})), V(0, 1, 0)), V(0, 0, 1));
    CHECK_NEAR(prism::transform_direction(in<Real>(prism::rotation(90.0, {0, 1, 0})), V(0, 0, 1)), V(1, 0, 0));
    // The axis need not be unit length.
    CHECK_NEAR(prism::transform_direction(in<Real>(prism::rotation(90.0, {0, 0, 5})), V(1, 0, 0)), V(0, 1, 0));
    // 120 degrees about the diagonal permutes the axes x -> y -> z.
    CHECK_NEAR(prism::transform_direction(in<Real>(prism::rotation(120.0, {1, 1, 1})), V(1, 0, 0)), V(0, 1, 0));
    // 20 degrees about z, as simple_transform.xml's r1: (cos 20, sin 20, 0).
    CHECK_NEAR(prism::transform_point(in<Real>(prism::rotation(20.0, {0, 0, 1})), V(1, 0, 0)),
               V(Real(0.93969262078590838), Real(0.34202014332566873), 0));
}

TEST_CASE_TEMPLATE("composite matrices are read row by row", Real, float, double) {
    using V = prism::Vec3<Real>;
    const glm::dmat4 m = prism::composite_from_row_major({1, 0, 0, 5,  //
                                                          0, 2, 0, 6,  //
                                                          0, 0, 3, 7,  //
                                                          0, 0, 0, 1});
    CHECK(m[3][0] == 5.0);  // GLM: [column][row]
    CHECK(m[1][1] == 2.0);
    CHECK_NEAR(prism::transform_point(in<Real>(m), V(1, 1, 1)), V(6, 8, 10));
    const glm::dmat4 counting = prism::composite_from_row_major({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16});
    CHECK(counting[0][1] == 5.0);  // row 1, column 0
    CHECK(counting[1][0] == 2.0);  // row 0, column 1
}

TEST_CASE_TEMPLATE("a point goes there and back through the inverse", Real, float, double) {
    using V = prism::Vec3<Real>;
    const glm::dmat4 m = prism::translation({3, -1, 2}) * prism::rotation(37.0, {1, 2, 3}) * prism::scaling({2, 0.5, 4});
    const auto forward = in<Real>(m);
    const auto backward = in<Real>(glm::inverse(m));
    const V p(Real(0.25), Real(-1.5), Real(2.0));
    const V there = prism::transform_point(forward, p);
    CHECK_FALSE(near(there, p));
    CHECK_NEAR(prism::transform_point(backward, there), p);
    const V d(Real(1), Real(2), Real(-3));
    CHECK_NEAR(prism::transform_direction(backward, prism::transform_direction(forward, d)), d);
}

TEST_CASE_TEMPLATE("normals stay perpendicular to tangents under non-uniform scaling", Real, float, double) {
    using V = prism::Vec3<Real>;
    const glm::dmat4 m = prism::rotation(30.0, {1, 2, 3}) * prism::scaling({1, 4, 0.25});
    const auto matrix = in<Real>(m);
    const V tangent_u = glm::normalize(V(1, 1, 0));
    const V tangent_v = glm::normalize(V(0, 1, 2));
    const V normal = glm::cross(tangent_u, tangent_v);
    const V u = prism::transform_direction(matrix, tangent_u);
    const V v = prism::transform_direction(matrix, tangent_v);
    const V n = glm::normalize(prism::transform_normal(matrix, normal));
    CHECK(std::abs(glm::dot(n, glm::normalize(u))) <= tolerance<Real>());
    CHECK(std::abs(glm::dot(n, glm::normalize(v))) <= tolerance<Real>());
    // Transforming the normal as a direction would not keep it perpendicular: the test can fail.
    const V wrong = glm::normalize(prism::transform_direction(matrix, normal));
    CHECK(std::abs(glm::dot(wrong, glm::normalize(u))) > Real(0.01));
    // The precomputed normal matrix gives the same normal.
    CHECK_NEAR(glm::normalize(prism::transform_normal(prism::normal_matrix(matrix), normal)), n);
}
