// Whether a text (an error message, a file written) holds a part: the tests' one spelling of
// std::string's C++23 contains. One definition for every test file, as the unity groups
// (tests/CMakeLists.txt) compile several files as one translation unit.
#pragma once

#include <string_view>

namespace prism_test {

inline bool contains(std::string_view text, std::string_view part) { return text.find(part) != std::string_view::npos; }

}  // namespace prism_test
