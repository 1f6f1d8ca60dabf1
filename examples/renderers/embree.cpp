// The shipped renderers through Embree (--accelerator embree), compiled once for every program
// that links prism_shipped_renderers (include/prism/render/render_scene.hpp,
// PRISM_SEPARATE_RENDERERS). Built only when Embree 3 is found.
#include <prism/render/render_scene.hpp>

namespace prism::detail {
PRISM_SHIPPED_RENDERERS(, EmbreeShippedConfigs)
}  // namespace prism::detail
