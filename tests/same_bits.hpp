// Whether two values are the same to the bit: what the tests mean by "the same answer" where a
// renderer or a kernel promises bit-identical results (== would call -0 and +0 equal and a NaN
// unequal to itself). One definition for every test file, as the unity groups
// (tests/CMakeLists.txt) compile several files as one translation unit.
#pragma once

#include <cstring>
#include <type_traits>

namespace prism_test {

template <class T>
    requires std::is_trivially_copyable_v<T>
bool same_bits(const T& a, const T& b) {
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}

}  // namespace prism_test
