// Loads the Embree renderers' module (embree_module.cpp) the first time --accelerator embree
// asks for it: render_scene.hpp's embree_module_renderer() for programs built with
// PRISM_EMBREE_MODULE. The module is looked for next to the executable (the build tree) and
// then at PRISM_EMBREE_MODULE_INSTALLED, relative to the executable's folder (an installation).
#include <prism/render/render_scene.hpp>

#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>

namespace prism::detail {

RenderFunction* embree_module_renderer() {
    // A failed load throws and is tried again by the next call; a loaded module stays loaded
    // (the images it rendered are freed after the render, by this program).
    static RenderFunction* const entry = [] {
        std::error_code error;
        const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", error);
        if (error) throw std::runtime_error("--accelerator embree: cannot find the prism executable's folder: " + error.message());
        const std::filesystem::path folder = program.parent_path();
        const std::filesystem::path candidates[] = {folder / PRISM_EMBREE_MODULE_NAME,
                                                    folder / PRISM_EMBREE_MODULE_INSTALLED / PRISM_EMBREE_MODULE_NAME};
        const std::filesystem::path* found = nullptr;
        for (const std::filesystem::path& candidate : candidates)
            if (std::filesystem::exists(candidate, error)) {
                found = &candidate;
                break;
            }
        if (!found)
            throw std::runtime_error("--accelerator embree: the Embree module " + candidates[0].string() + " (or " +
                                     candidates[1].lexically_normal().string() + ") is missing");
        void* module = ::dlopen(found->c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!module) {
            const char* reason = ::dlerror();
            throw std::runtime_error("--accelerator embree: cannot load the Embree module: " +
                                     std::string(reason ? reason : found->string()));
        }
        using Entry = RenderFunction* (*)();
        const auto get = reinterpret_cast<Entry>(::dlsym(module, "prism_embree_renderer"));
        if (!get) throw std::runtime_error("--accelerator embree: " + found->string() + " is not prism's Embree module");
        return get();
    }();
    return entry;
}

}  // namespace prism::detail
