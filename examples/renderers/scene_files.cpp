// The scene files' readers and interpreter, compiled once for every program of this project
// that links prism_scene_files (include/prism/io/load.hpp, PRISM_SEPARATE_SCENE_FILES).
#define PRISM_SCENE_FILES_DEFINED_HERE
#include <prism/io/load.hpp>
