// PLACEHOLDER for the scene-level entry point: renders every camera of a plain scene description
// with a renderer configuration chosen from the scene. The interface is fixed; the body is not.
#pragma once

#include <prism/image/image.hpp>
#include <prism/scene/scene.hpp>

#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace prism {

enum class Precision { single, double_refine, double_all };

struct RenderOptions {
    int threads = 0;                      // 0: all hardware threads
    std::optional<Precision> precision;   // empty: chosen from the scene
    double resolution_scale = 1.0;        // < 1 renders a reduced image (suite, quick checks)
    bool progress = false;                // progress bar on stderr
};

struct CameraImage {
    std::size_t camera = 0;   // index into Scene::cameras
    std::string image_name;   // Camera::image_name
    Image image;              // linear radiance
    double seconds = 0.0;     // render time of this camera (excludes loading and BVH build)
};

inline std::vector<CameraImage> render_scene(const scene::Scene&, const RenderOptions&, std::ostream& /*log*/) {
    throw std::logic_error("render_scene not implemented yet");
}

}  // namespace prism
