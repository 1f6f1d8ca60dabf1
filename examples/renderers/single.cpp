// The shipped renderers of one precision, compiled once for every program that links
// prism_shipped_renderers (include/prism/render/render_scene.hpp, PRISM_SEPARATE_RENDERERS).
#include <prism/render/render_scene.hpp>

namespace prism::detail {
PRISM_SHIPPED_RENDERERS(, ShippedConfigs<Precision::single>)
}  // namespace prism::detail
