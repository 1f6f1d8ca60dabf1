// prism: renders every camera of a CENG795 scene file (XML or JSON) into its image file.
// All cameras are rendered before any file is written, so a failure leaves no partial output.
#include "../common/command_line.hpp"

#include <prism/image/image_io.hpp>
#include <prism/image/tonemap.hpp>
#include <prism/io/load.hpp>
#include <prism/render/progress.hpp>
#include <prism/render/render_scene.hpp>

#include <charconv>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace {

const prism::CommandLine command_line("prism");

constexpr const char* usage = R"(usage: prism SCENE [options]

Renders every camera of SCENE (a CENG795 .xml or .json scene file) and writes each camera's
image under the name the scene gives it (.png: clamped to 0-255; .exr: linear radiance). Each
<Tonemap> of a camera adds an 8-bit image tone-mapped from the same render, named by the image
name's stem and the Tonemap's <Extension>; a .png image name with Tonemaps is tone-mapped itself.

options:
  --output-dir DIR     folder for the images (default: the current folder); created if missing
  --threads N          worker threads (default: all hardware threads)
  --precision P        float | double-refine | double: override the precision chosen from the
                       scene (the choice and its reason are printed)
  --scale S            render at S times the cameras' resolution (0 < S <= 1; quick previews)
  --max-samples N      at most N samples per pixel, whatever NumSamples says (quick previews)
  --ray-offset M       how rays leave surfaces: scene-epsilon (the scene's ShadowRayEpsilon
                       along the normal, as the course renders) or error-bound (past the hit
                       point's floating-point error bound: no tuned number). Default: the
                       epsilon, unless it is below 64 ulps of the scene's largest coordinate
  --seed N             selects the pixels' random streams (default 0); any thread count gives
                       the same image for the same seed
  --accelerator A      prism (its own BVH; the default) or embree: Embree 3 finds the hits,
                       prism tests the triangle it finds and shades (float; only when built
                       with libembree-dev)
  --untyped-mirrors M  a material with no type but a MirrorReflectance: ignore (Blinn-Phong only,
                       as the course's images of 2021-2025 scenes show; the default) or
                       reflect (a mirror, as 2017-2019 scene files, written before material
                       types existed, mean it)
  --cull-backfaces     primary rays ignore triangles facing away from the camera
  --quiet              print nothing but errors
  --help               this text

exit status: 0 on success; 1 when the scene cannot be loaded, rendered or written (one line on
stderr names the file and the element at fault, and no image is written); 2 for usage errors.
)";

struct Arguments {
    std::filesystem::path scene;
    std::filesystem::path output_dir = ".";
    prism::RenderOptions options;
    prism::io::LoadOptions load;
    bool quiet = false;
};

Arguments parse_arguments(int argc, char** argv) {
    Arguments arguments;
    std::vector<std::string_view> args(argv + 1, argv + argc);
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string_view arg = args[i];
        const auto value = [&]() -> std::string_view {
            if (i + 1 >= args.size()) command_line.usage_error(std::string(arg) + " needs a value");
            return args[++i];
        };
        if (arg == "--help" || arg == "-h") {
            std::cout << usage;
            std::exit(0);
        } else if (command_line.render_option(arg, value, arguments.options)) {
            continue;
        } else if (arg == "--output-dir") {
            arguments.output_dir = std::filesystem::path(value());
        } else if (arg == "--untyped-mirrors") {
            const std::string_view mode = value();
            if (mode == "reflect") arguments.load.untyped_mirrors_reflect = true;
            else if (mode == "ignore") arguments.load.untyped_mirrors_reflect = false;
            else command_line.usage_error("--untyped-mirrors must be reflect or ignore");
        } else if (arg == "--cull-backfaces") {
            arguments.options.cull_backfaces = true;
        } else if (arg == "--quiet") {
            arguments.quiet = true;
        } else if (!arg.empty() && arg[0] == '-') {
            command_line.usage_error("unknown option " + std::string(arg));
        } else if (arguments.scene.empty()) {
            arguments.scene = std::filesystem::path(arg);
        } else {
            command_line.usage_error("more than one scene given");
        }
    }
    if (arguments.scene.empty()) command_line.usage_error("no scene given");
    return arguments;
}

}  // namespace

int main(int argc, char** argv) {
    const Arguments arguments = parse_arguments(argc, argv);
    std::ostringstream silent;
    std::ostream& log = arguments.quiet ? static_cast<std::ostream&>(silent) : std::cout;
    try {
        const prism::scene::Scene scene = prism::io::load_scene(arguments.scene, arguments.load);
        if (scene.cameras.empty()) throw prism::io::LoadError(arguments.scene, "<Cameras>", "the scene has no camera");

        const std::size_t total_pixels = prism::total_pixels(scene, arguments.options);
        prism::ProgressBar progress(total_pixels, !arguments.quiet);
        const auto images = prism::render_scene(scene, arguments.options, log,
                                                [&](std::size_t, int pixels) { progress.advance(std::size_t(pixels)); });
        progress.finish();

        for (const auto& rendered : images) {
            const prism::scene::Camera& camera = scene.cameras[rendered.camera];
            log << "camera " << camera.id << ": " << rendered.image.width << "x" << rendered.image.height
                << " rendered in " << rendered.seconds << " s\n";
            // Every file of the camera comes from this one render: no tone mapping re-traces.
            for (const prism::CameraOutput& output : prism::camera_outputs(camera)) {
                const std::filesystem::path path = arguments.output_dir / output.name;
                if (output.tonemap) prism::write_image(path, prism::tone_map(rendered.image, camera.tonemaps[*output.tonemap]));
                else prism::write_image(path, rendered.image);
                log << "  " << path.string() << '\n';
            }
        }
    } catch (const std::exception& error) {
        std::cerr << "prism: " << error.what() << '\n';
        return 1;
    }
    return 0;
}
