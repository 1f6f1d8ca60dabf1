// The choices a caller makes about how a scene file is read (io/load.hpp, io/scene_loader.hpp),
// apart from the interpreter, so that a program that only calls load_scene can name them without
// compiling the readers.
#pragma once

#include <prism/io/limits.hpp>

namespace prism::io {

// Choices of interpretation that the files themselves cannot settle.
struct LoadOptions {
    // A material with no type but a MirrorReflectance: Blinn-Phong only (false: what the
    // course's images of 2021-2025 files show) or a mirror (true: what 2017-2019 files meant,
    // when the course's files had no material types; cornellbox_glossy's untyped spheres with
    // a Roughness are glossy mirrors). No file says which year's rules it follows.
    bool untyped_mirrors_reflect = false;
    // What a file may ask for (limits.hpp); prism --max-recursion-depth raises the depth.
    ResourceLimits limits;
};

}  // namespace prism::io
