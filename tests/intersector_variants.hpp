// The (triangle intersector, scalar type) pairs the tests run, as one type each, so that a
// TEST_CASE_TEMPLATE instantiated over them names both halves of a failing pair.
#pragma once

#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/naive_epsilon.hpp>
#include <prism/geometry/watertight.hpp>

namespace prism_test {

template <class IntersectorT, class RealT>
struct Variant {
    using Intersector = IntersectorT;
    using Real = RealT;
};
using WatertightFloat = Variant<prism::Watertight, float>;
using WatertightDouble = Variant<prism::Watertight, double>;
using DoubleRefineFloat = Variant<prism::DoubleRefine, float>;
using NaiveFloat = Variant<prism::NaiveEpsilon, float>;
using NaiveDouble = Variant<prism::NaiveEpsilon, double>;

}  // namespace prism_test
