// prism-envmap: writes an environment map for the course's SphericalDirectionalLight, in the
// lat-long or light-probe layout, as a linear float EXR: a procedural sky (gradient and sun
// disc, light/procedural_sky.hpp) or a constant environment (a white furnace).
#include "../common/command_line.hpp"

#include <prism/image/image_io.hpp>
#include <prism/light/procedural_sky.hpp>

#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace {

const prism::CommandLine command_line("prism-envmap");

constexpr const char* usage = R"(usage: prism-envmap [options] --output FILE.exr

Writes an environment map (linear float RGB EXR) for a SphericalDirectionalLight: a sky with a
vertical gradient (horizon colour to zenith colour above the horizon, a flat ground colour
below) and a sun disc, or a constant environment.

layout (the course's mappings):
  --layout L             latlong (default): u = (1 + atan2(x, -z) / pi) / 2, v = acos(y) / pi,
                         WIDTH x WIDTH/2 pixels; or probe (angular map): centre -Z, right +X,
                         up +Y, rim +Z, WIDTH x WIDTH pixels, black outside the disc
  --width N              image width in pixels, 2 to 16384 (default 1024)
  --samples N            N x N directions averaged per pixel, 1 to 16 (default 4)

sky:
  --horizon R,G,B        radiance at the horizon (default 0.9,0.95,1)
  --zenith R,G,B         radiance straight up (default 0.25,0.45,0.9)
  --ground R,G,B         radiance from below the horizon (default 0.3,0.27,0.25)
  --sun-direction X,Y,Z  towards the sun, any length but zero (default 0.5,0.6,-0.6)
  --sun-angle DEG        the sun disc's full angular diameter, in (0, 180] (default 3)
  --sun-radiance R,G,B   the sun disc's radiance; 0,0,0 for no sun (default 1000,950,850)

constant:
  --constant R,G,B       the same radiance from every direction instead of the sky (not
                         combinable with the sky options)

  --output FILE.exr      the file to write (required); it appears whole or not at all
  --help                 this text

Example: a sunset-like sky in the probe layout
  prism-envmap --layout probe --width 512 --sun-direction 1,0.1,-1 --sun-radiance 2000,900,300 \
      --output sky_probe.exr

exit status: 0 on success, 1 when the file cannot be written, 2 for usage errors (nothing is
written).
)";

struct Arguments {
    prism::scene::EnvironmentLayout layout = prism::scene::EnvironmentLayout::latlong;
    int width = 1024;
    int samples = 4;
    prism::ProceduralSky sky{.horizon = {0.9, 0.95, 1.0},
                             .zenith = {0.25, 0.45, 0.9},
                             .ground = {0.3, 0.27, 0.25},
                             .sun_direction = {0.5, 0.6, -0.6},
                             .sun_angle_degrees = 3.0,
                             .sun_radiance = {1000.0, 950.0, 850.0}};
    std::optional<glm::dvec3> constant;
    std::filesystem::path output;
};

// "a,b,c": exactly three finite numbers.
glm::dvec3 triple(std::string_view option, std::string_view text) {
    std::vector<double> values;
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = text.find(',', start);
        const std::string_view part = text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
        const double value = command_line.number<double>(option, part);
        if (!std::isfinite(value)) command_line.usage_error(std::string(option) + ": not a finite number: '" + std::string(part) + "'");
        values.push_back(value);
        if (comma == std::string_view::npos) break;
        start = comma + 1;
    }
    if (values.size() != 3)
        command_line.usage_error(std::string(option) + " needs three comma-separated numbers, got '" + std::string(text) + "'");
    return {values[0], values[1], values[2]};
}

glm::dvec3 radiance(std::string_view option, std::string_view text) {
    const glm::dvec3 value = triple(option, text);
    if (value.x < 0 || value.y < 0 || value.z < 0) command_line.usage_error(std::string(option) + " must not be negative");
    return value;
}

Arguments parse_arguments(int argc, char** argv) {
    Arguments arguments;
    std::vector<std::string_view> args(argv + 1, argv + argc);
    std::vector<std::string_view> seen;
    std::string_view sky_option;  // the first sky option given, for the --constant conflict
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string_view arg = args[i];
        const auto value = [&]() -> std::string_view {
            if (i + 1 >= args.size()) command_line.usage_error(std::string(arg) + " needs a value");
            return args[++i];
        };
        if (arg == "--help" || arg == "-h") {
            std::cout << usage;
            std::exit(0);
        }
        for (const std::string_view earlier : seen)
            if (earlier == arg) command_line.usage_error(std::string(arg) + " given twice");
        seen.push_back(arg);
        const bool is_sky_option = arg == "--horizon" || arg == "--zenith" || arg == "--ground" ||
                                   arg == "--sun-direction" || arg == "--sun-angle" || arg == "--sun-radiance";
        if (is_sky_option && sky_option.empty()) sky_option = arg;

        if (arg == "--layout") {
            const std::string_view layout = value();
            if (layout == "latlong") arguments.layout = prism::scene::EnvironmentLayout::latlong;
            else if (layout == "probe") arguments.layout = prism::scene::EnvironmentLayout::probe;
            else command_line.usage_error("--layout must be latlong or probe, not '" + std::string(layout) + "'");
        } else if (arg == "--width") {
            arguments.width = command_line.number<int>(arg, value());
            if (arguments.width < 2 || arguments.width > 16384) command_line.usage_error("--width must be in 2..16384");
        } else if (arg == "--samples") {
            arguments.samples = command_line.number<int>(arg, value());
            if (arguments.samples < 1 || arguments.samples > 16) command_line.usage_error("--samples must be in 1..16");
        } else if (arg == "--horizon") {
            arguments.sky.horizon = radiance(arg, value());
        } else if (arg == "--zenith") {
            arguments.sky.zenith = radiance(arg, value());
        } else if (arg == "--ground") {
            arguments.sky.ground = radiance(arg, value());
        } else if (arg == "--sun-direction") {
            arguments.sky.sun_direction = triple(arg, value());
            if (glm::length(arguments.sky.sun_direction) == 0) command_line.usage_error("--sun-direction must not be 0,0,0");
        } else if (arg == "--sun-angle") {
            arguments.sky.sun_angle_degrees = command_line.number<double>(arg, value());
            if (!(arguments.sky.sun_angle_degrees > 0 && arguments.sky.sun_angle_degrees <= 180))
                command_line.usage_error("--sun-angle must be in (0, 180] degrees");
        } else if (arg == "--sun-radiance") {
            arguments.sky.sun_radiance = radiance(arg, value());
        } else if (arg == "--constant") {
            arguments.constant = radiance(arg, value());
        } else if (arg == "--output") {
            arguments.output = std::filesystem::path(value());
        } else if (!arg.empty() && arg[0] == '-') {
            command_line.usage_error("unknown option " + std::string(arg));
        } else {
            command_line.usage_error("unexpected argument '" + std::string(arg) + "'");
        }
    }
    if (arguments.constant && !sky_option.empty())
        command_line.usage_error("--constant makes a constant map: " + std::string(sky_option) + " does not apply");
    if (arguments.output.empty()) command_line.usage_error("no --output FILE.exr given");
    if (arguments.output.extension() != ".exr") command_line.usage_error("--output must name an .exr file");
    if (arguments.output.stem().empty()) command_line.usage_error("--output needs a file name");
    return arguments;
}

}  // namespace

int main(int argc, char** argv) {
    const Arguments arguments = parse_arguments(argc, argv);
    try {
        const prism::Image image =
            arguments.constant ? prism::render_constant(*arguments.constant, arguments.layout, arguments.width, arguments.samples)
                               : prism::render_sky(arguments.sky, arguments.layout, arguments.width, arguments.samples);
        prism::write_image(arguments.output, image);
        std::cout << arguments.output.string() << ": " << image.width << "x" << image.height << " "
                  << (arguments.layout == prism::scene::EnvironmentLayout::latlong ? "lat-long" : "light probe") << '\n';
    } catch (const std::exception& error) {
        std::cerr << "prism-envmap: " << error.what() << '\n';
        return 1;
    }
    return 0;
}
