// prism: renders every camera of a CENG795 scene file (XML or JSON) into its image file.
// All cameras are rendered before any file is written, so a failure leaves no partial output.
// Every image goes inside --output-dir (io/output_path.hpp); Ctrl-C stops the render and writes
// nothing, or, while files are being written, stops before the next file.
#include "../common/command_line.hpp"

#include <prism/image/image_io.hpp>
#include <prism/image/tonemap.hpp>
#include <prism/io/element.hpp>
#include <prism/io/limits.hpp>
#include <prism/io/load_error.hpp>
#include <prism/io/load.hpp>
#include <prism/io/output_path.hpp>
#include <prism/render/progress.hpp>
#include <prism/render/render_scene.hpp>

#include <tbb/global_control.h>

#include <atomic>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <new>
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
  --output-dir DIR     folder for the images (default: the current folder); created if missing.
                       An ImageName that is absolute or leaves DIR (`..`, a link) is refused
  --threads N          worker threads (default: all hardware threads)
  --precision P        float | double-refine | double: override the precision chosen from the
                       scene (the choice and its reason are printed)
  --scale S            render at S times the cameras' resolution (0 < S <= 1; quick previews)
  --samples N          N samples per pixel, whatever NumSamples says (before --max-samples)
  --max-samples N      at most N samples per pixel, whatever NumSamples says (quick previews)
  --ray-offset M       how rays leave surfaces: scene-epsilon (the scene's ShadowRayEpsilon
                       along the normal, as the course renders) or error-bound (past the hit
                       point's floating-point error bound: no tuned number). Default: the
                       epsilon, unless it is below 64 ulps of the scene's largest coordinate
  --seed N             seeds the sampler's numbers (default 0); any thread count gives
                       the same image for the same seed
  --sampler S          independent | stratified | sobol: where each sample's numbers come from
                       (the pixel's random stream; every dimension stratified across the
                       pixel's samples; Owen-scrambled Sobol' points in Morton order, pbrt-v4's
                       ZSobol). Default: sobol
  --accelerator A      prism (its own BVH; the default) or embree: Embree 3 finds the hits,
                       prism tests the triangle it finds and shades (float; only when built
                       with libembree-dev)
  --untyped-mirrors M  a material with no type but a MirrorReflectance: ignore (Blinn-Phong only,
                       as the course's images of 2021-2025 scenes show; the default) or
                       reflect (a mirror, as 2017-2019 scene files, written before material
                       types existed, mean it)
  --cull-backfaces     camera rays ignore every triangle and plane facing away from them
  --no-cull-backfaces  camera rays see every surface from both sides. Default (neither): the
                       course's rule, camera rays ignore back-facing triangles of every mesh
                       and see spheres and planes from both sides
  --max-recursion-depth N
                       the largest MaxRecursionDepth a scene may ask for (default 64; at most
                       512, the depth the renderer's stack is known to hold)
  --quiet              print nothing but errors
  --help               this text

Ctrl-C during the render stops it and writes nothing; during writing, the images already written
stay (each complete: images are written to a temporary file and renamed into place) and no
further one is started. A second Ctrl-C ends prism at once.

exit status: 0 on success; 1 when the scene cannot be loaded, rendered or written (one line on
stderr names the file and the element at fault, and no image is written); 2 for usage errors;
130 when interrupted.
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
        } else if (arg == "--max-recursion-depth") {
            const int depth = command_line.number<int>(arg, value());
            if (depth < 0 || depth > prism::io::stack_safe_recursion_depth)
                command_line.usage_error("--max-recursion-depth must be between 0 and " +
                                         std::to_string(prism::io::stack_safe_recursion_depth));
            arguments.load.limits.max_recursion_depth = depth;
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

// Ctrl-C: the first one asks prism to stop (checked after loading and after every tile) and
// restores the default action, so that a second one ends the program at once.
std::atomic<bool> interrupted{false};

extern "C" void on_interrupt(int) {
    interrupted.store(true);
    std::signal(SIGINT, SIG_DFL);
}

struct Interrupted {};

}  // namespace

int main(int argc, char** argv) {
    const Arguments arguments = parse_arguments(argc, argv);
    std::ostringstream silent;
    std::ostream& log = arguments.quiet ? static_cast<std::ostream&>(silent) : std::cout;
    std::signal(SIGINT, on_interrupt);
    // --threads bounds the image encoding too (png_encoder.hpp), not only the render.
    std::optional<tbb::global_control> parallelism;
    if (arguments.options.threads > 0)
        parallelism.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(arguments.options.threads));
    try {
        const prism::scene::Scene scene = prism::io::load_scene(arguments.scene, arguments.load);
        if (interrupted.load()) throw Interrupted{};
        if (scene.cameras.empty()) throw prism::io::LoadError(arguments.scene, "<Cameras>", "the scene has no camera");

        // Every output's place is checked before the render, so a refused name costs no render time.
        std::vector<std::vector<std::filesystem::path>> paths;
        for (const prism::scene::Camera& camera : scene.cameras) {
            const std::string element = prism::io::element_label("Camera", &camera.id) + "/<ImageName>";
            paths.emplace_back();
            for (const prism::CameraOutput& output : prism::camera_outputs(camera)) {
                paths.back().push_back(
                    prism::io::confined_output_path(arguments.output_dir, output.name, arguments.scene, element));
                if (const std::optional<std::string> problem = prism::unwritable_format(output.name))
                    throw prism::io::LoadError(arguments.scene, element, "\"" + output.name.string() + "\": " + *problem);
            }
        }

        prism::io::prepare_output_folder(arguments.output_dir);

        const std::size_t total_pixels = prism::total_pixels(scene, arguments.options);
        prism::ProgressBar progress(total_pixels, !arguments.quiet);
        // An exception thrown from a tile cancels the parallel render and reaches this thread.
        const auto images = prism::render_scene(scene, arguments.options, log, [&](std::size_t, int pixels) {
            if (interrupted.load()) throw Interrupted{};
            progress.advance(std::size_t(pixels));
        });
        if (interrupted.load()) throw Interrupted{};
        progress.finish();

        for (const auto& rendered : images) {
            const prism::scene::Camera& camera = scene.cameras[rendered.camera];
            log << "camera " << camera.id << ": " << rendered.image.width << "x" << rendered.image.height
                << " rendered in " << rendered.seconds << " s\n";
            // Every file of the camera comes from this one render: no tone mapping re-traces.
            const std::vector<prism::CameraOutput> outputs = prism::camera_outputs(camera);
            for (std::size_t o = 0; o < outputs.size(); ++o) {
                if (interrupted.load()) throw Interrupted{};
                const prism::CameraOutput& output = outputs[o];
                const std::filesystem::path& path = paths[rendered.camera][o];
                if (output.tonemap) prism::write_image(path, prism::tone_map(rendered.image, camera.tonemaps[*output.tonemap]));
                else prism::write_image(path, rendered.image);
                log << "  " << path.string() << '\n';
            }
        }
    } catch (const Interrupted&) {
        std::cerr << "prism: interrupted (Ctrl-C): the images written before it are complete, no other was written\n";
        return 130;
    } catch (const prism::io::LoadError& error) {
        std::cerr << "prism: " << error.what() << '\n';
        return 1;
    } catch (const std::bad_alloc&) {
        // The limits (io/limits.hpp) keep a scene's own requests in bounds; this is the machine
        // running out of memory for what is left (a large mesh, many threads' worth of tiles).
        std::cerr << "prism: " << arguments.scene.string() << ": out of memory while loading or rendering the scene\n";
        return 1;
    } catch (const std::exception& error) {
        std::cerr << "prism: " << arguments.scene.string() << ": " << error.what() << '\n';
        return 1;
    }
    return 0;
}
