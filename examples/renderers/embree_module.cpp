// The shipped renderers through Embree as a module the prism renderer loads only for
// --accelerator embree (include/prism/render/render_scene.hpp, PRISM_EMBREE_MODULE), so that its
// other runs do not load libembree3. Built only when Embree 3 is found. This file is the entry
// point alone: the renderers are embree.cpp's (prism_embree_renderers), which the tests and
// prism-suite link too.
#include <prism/render/render_scene.hpp>

namespace {

std::vector<prism::CameraImage> render(const prism::scene::Needs& needs, const prism::scene::Scene& scene,
                                       const prism::RenderOptions& options, std::ostream& log,
                                       const std::function<void(std::size_t camera, int pixels)>& on_tile) {
    return prism::detail::render_first_covering(prism::EmbreeShippedConfigs{}, needs, scene, options, log, on_tile);
}

}  // namespace

// The module's one exported symbol (everything else is hidden: CMake's visibility preset).
extern "C" [[gnu::visibility("default")]] prism::detail::RenderFunction* prism_embree_renderer() { return &render; }
