# The README's include-and-go program is examples/minimal/main.cpp, character for character: the
# package tests build and run that file, so the README shows a program known to compile and work.
#   cmake -DREADME=README.md -DEXAMPLE=examples/minimal/main.cpp -P check_readme_example.cmake
file(READ "${README}" readme)
file(READ "${EXAMPLE}" example)
string(FIND "${readme}" "```cpp\n${example}```" found)
if(found EQUAL -1)
  message(FATAL_ERROR "README.md has no ```cpp block equal to ${EXAMPLE}: copy the file into the README again")
endif()
message(STATUS "README.md shows ${EXAMPLE} whole")
