// The interpreter both scene harnesses run (scene_harness.hpp), compiled once.
#include "scene_harness.hpp"

#include <prism/io/scene_loader.hpp>

namespace prism::fuzz {

void interpret_tree(const io::Element& tree, const std::filesystem::path& path) {
    const scene::Scene scene = io::interpret_scene(tree, path);
    (void)scene;
}

}  // namespace prism::fuzz
