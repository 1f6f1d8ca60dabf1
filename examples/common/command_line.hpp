// What the example programs share on their command lines: a usage error is one line on stderr
// and exit status 2, numbers parse whole or not at all, and every program that renders takes the
// same --threads, --precision, --scale, --samples, --max-samples, --ray-offset, --seed and --sampler with the
// same checks.
#pragma once

#include <prism/io/limits.hpp>
#include <prism/render/render_scene.hpp>

#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <string>
#include <string_view>

namespace prism {

class CommandLine {
public:
    explicit CommandLine(std::string_view program) : program_(program) {}

    [[noreturn]] void usage_error(const std::string& message) const {
        std::cerr << program_ << ": " << message << "\n(see " << program_ << " --help)\n";
        std::exit(2);
    }

    template <class Number>
    Number number(std::string_view option, std::string_view text) const {
        Number value{};
        const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (error != std::errc() || end != text.data() + text.size())
            usage_error(std::string(option) + ": not a number: '" + std::string(text) + "'");
        return value;
    }

    // Reads `option` into `options` when it is one of the rendering options, taking its value
    // from next_value(); returns whether it was.
    template <class NextValue>
    bool render_option(std::string_view option, NextValue&& next_value, RenderOptions& options) const {
        if (option == "--threads") {
            options.threads = number<int>(option, next_value());
            if (options.threads < 1) usage_error("--threads must be at least 1");
        } else if (option == "--precision") {
            const std::string_view precision = next_value();
            if (precision == "float") options.precision = Precision::single;
            else if (precision == "double-refine") options.precision = Precision::double_refine;
            else if (precision == "double") options.precision = Precision::double_all;
            else usage_error("--precision must be float, double-refine or double");
        } else if (option == "--scale") {
            options.resolution_scale = number<double>(option, next_value());
            if (!(options.resolution_scale > 0 && options.resolution_scale <= 1)) usage_error("--scale must be in (0, 1]");
        } else if (option == "--max-samples") {
            options.max_samples = number<int>(option, next_value());
            if (options.max_samples < 1) usage_error("--max-samples must be at least 1");
        } else if (option == "--samples") {
            options.samples = number<int>(option, next_value());
            if (options.samples < 1 || options.samples > io::max_samples_per_pixel)
                usage_error("--samples must be in [1, " + std::to_string(io::max_samples_per_pixel) + "]");
        } else if (option == "--ray-offset") {
            const std::string_view mode = next_value();
            if (mode == "error-bound") options.ray_offset = RayOffset::error_bound;
            else if (mode == "scene-epsilon") options.ray_offset = RayOffset::scene_epsilon;
            else usage_error("--ray-offset must be error-bound or scene-epsilon");
        } else if (option == "--accelerator") {
            const std::string_view accelerator = next_value();
            if (accelerator == "prism") options.accelerator = AcceleratorChoice::prism;
            else if (accelerator == "embree") options.accelerator = AcceleratorChoice::embree;
            else usage_error("--accelerator must be prism or embree");
            if (options.accelerator == AcceleratorChoice::embree && !embree_available)
                usage_error("--accelerator embree: this prism was built without Embree 3 (libembree-dev)");
        } else if (option == "--cull-backfaces" || option == "--no-cull-backfaces") {
            // Both given is a contradiction, not "the last one wins": say so rather than guess.
            const BackfaceCulling chosen = option == "--cull-backfaces" ? BackfaceCulling::all : BackfaceCulling::none;
            const BackfaceCulling other = chosen == BackfaceCulling::all ? BackfaceCulling::none : BackfaceCulling::all;
            if (options.backface_culling == other)
                usage_error("--cull-backfaces and --no-cull-backfaces contradict each other: give one");
            options.backface_culling = chosen;
        } else if (option == "--seed") {
            options.seed = number<std::uint64_t>(option, next_value());
        } else if (option == "--sampler") {
            const std::string_view name = next_value();
            options.sampler = parse_sampler(name);
            if (!options.sampler) usage_error("--sampler must be independent, stratified or sobol");
        } else {
            return false;
        }
        return true;
    }

private:
    std::string_view program_;
};

}  // namespace prism
