# The packages prism::prism depends on, found the same way by the build tree and by an installed
# prismConfig.cmake. All come from Debian packages (see docs/architecture.md); stb has no CMake config there,
# so its library and headers are found by hand and wrapped in an imported target.
include(CMakeFindDependencyMacro)
find_dependency(glm CONFIG)
find_dependency(pugixml CONFIG)
find_dependency(nlohmann_json CONFIG)
find_dependency(TBB CONFIG)
find_dependency(tinyexr CONFIG)
find_dependency(ZLIB)  # PNG writing (image/image_io.hpp); zlib1g-dev, which tinyexr needs too

if(NOT TARGET prism::stb)
  find_path(PRISM_STB_INCLUDE_DIR stb_image.h PATH_SUFFIXES stb)
  find_library(PRISM_STB_LIBRARY stb)
  if(NOT PRISM_STB_INCLUDE_DIR OR NOT PRISM_STB_LIBRARY)
    message(FATAL_ERROR "prism: stb not found (Debian package libstb-dev)")
  endif()
  add_library(prism::stb UNKNOWN IMPORTED)
  set_target_properties(prism::stb PROPERTIES
    IMPORTED_LOCATION "${PRISM_STB_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${PRISM_STB_INCLUDE_DIR}")
endif()
