// The speed-against-accuracy chart (tracker issue 3): a set of scenes rendered with each
// (triangle intersector, precision, ray offset) variant, every image compared after the course's
// 8-bit conversion with a reference rendered by Watertight double with error-bound offsets from
// the same samples (same seed), and the render time of each. Writes the chart as SVG (the PNG is
// converted from it by tools/chart.sh, so both show the same chart), the numbers as TSV, and the
// table section of bench/RESULTS.md between its markers.
//
// Answers are checked before anything is written: every render of a variant must give the same
// image bit for bit (the reference also from a second, separately built renderer), every image
// has the reference's size, the reference must show the scene (not only background), and the
// dragons that are the same surface (moved, or subdivided less) must render the same reference
// image. A missing scene file stops the run before any rendering, naming the file.
#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/naive_epsilon.hpp>
#include <prism/geometry/watertight.hpp>
#include <prism/image/compare.hpp>
#include <prism/image/image_io.hpp>
#include <prism/io/load.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/render/renderer.hpp>
#include <prism/scene/stress.hpp>

#include "run_record.hpp"
#include "svg_plot.hpp"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <time.h>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

namespace fs = std::filesystem;
using namespace prism::bench;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// ---------------------------------------------------------------------------------------------
// What is rendered

// Renders a camera at a size; one per variant and scene, built (BVH included) before timing.
using RenderFunction = std::function<prism::Image(const prism::scene::Camera&, int width, int height)>;

// prism's own variants traverse the structure the shipped renderers build (render_scene.hpp's
// PrecisionPolicy): the wide BVH of this instruction set's width, its leaves' packets of the
// variant's triangle test.
template <class Real, class Intersector, class Acceleration = prism::WideBvh<Intersector, prism::wide_bvh_width>>
RenderFunction build_renderer(const prism::scene::Scene& scene, prism::RayOffset offset) {
    using Config = prism::Config<Real, Acceleration, prism::Lights<prism::PointLight>>;
    auto renderer = std::make_shared<const prism::Renderer<Config>>(scene, prism::RendererSettings{prism::BackfaceCulling::none, offset, 0, {}});
    return [renderer](const prism::scene::Camera& camera, int width, int height) {
        return renderer->render(camera, width, height);
    };
}

struct Variant {
    std::string name;    // legend and table
    std::string marker;  // SVG marker shape: circle, square, diamond, triangle_up, triangle_down, plus, star, cross
    RenderFunction (*build)(const prism::scene::Scene&);
};

// The reference is the last one: Watertight double with error-bound offsets.
const std::vector<Variant>& variants() {
    using prism::RayOffset;
    static const std::vector<Variant> list{
        {"NaiveEpsilon float, scene epsilon", "cross",
         [](const prism::scene::Scene& s) { return build_renderer<float, prism::NaiveEpsilon>(s, RayOffset::scene_epsilon); }},
        {"Watertight float, scene epsilon", "triangle_down",
         [](const prism::scene::Scene& s) { return build_renderer<float, prism::Watertight>(s, RayOffset::scene_epsilon); }},
        {"Watertight float, error bounds", "triangle_up",
         [](const prism::scene::Scene& s) { return build_renderer<float, prism::Watertight>(s, RayOffset::error_bound); }},
        {"DoubleRefine float, error bounds", "diamond",
         [](const prism::scene::Scene& s) { return build_renderer<float, prism::DoubleRefine>(s, RayOffset::error_bound); }},
#ifdef PRISM_WITH_EMBREE
        // Embree 3 traversing (accel/embree.hpp), prism's watertight float test on the triangle
        // it finds: where Embree's float traversal stands beside prism's own.
        {"Embree float, scene epsilon", "plus",
         [](const prism::scene::Scene& s) {
             return build_renderer<float, prism::Watertight, prism::Embree>(s, RayOffset::scene_epsilon);
         }},
        {"Embree float, error bounds", "star",
         [](const prism::scene::Scene& s) {
             return build_renderer<float, prism::Watertight, prism::Embree>(s, RayOffset::error_bound);
         }},
#endif
        {"Watertight double, scene epsilon", "square",
         [](const prism::scene::Scene& s) { return build_renderer<double, prism::Watertight>(s, RayOffset::scene_epsilon); }},
        {"Watertight double, error bounds (reference)", "circle",
         [](const prism::scene::Scene& s) { return build_renderer<double, prism::Watertight>(s, RayOffset::error_bound); }},
    };
    return list;
}

struct ChartScene {
    std::string name;         // legend and table
    std::string file;         // under the shared folder
    int subdivision_levels;   // of the largest mesh; 0 keeps the scene as it is
    prism::scene::Vec3 offset;  // the whole scene moved by this (scene/stress.hpp)
    std::string colour;
    std::string same_image_as;  // a scene whose reference image this one's must match, or empty
};

const std::string dragon_file = "ceng795/hw1/2020_ozgurcanc/assets/scenes/dragon_lowres.xml";
const std::string tiny_dragon = "tiny-triangle dragon (766,144 triangles)";

// Okabe-Ito colours: told apart with the common colour-vision deficiencies.
const std::vector<ChartScene>& chart_scenes() {
    static const std::vector<ChartScene> list{
        {tiny_dragon, dragon_file, 3, {0, 0, 0}, "#0072B2", ""},
        {"tiny-triangle dragon moved by (1e4, 1e4, 1e4)", dragon_file, 3, {1e4, 1e4, 1e4}, "#D55E00", tiny_dragon},
        {"dragon subdivided twice (191,536 triangles)", dragon_file, 2, {0, 0, 0}, "#009E73", tiny_dragon},
        {"hw1 ton_Roosendaal_smooth (78,620 triangles)",
         "ceng795/hw1/2022F_Batucan2601/System_Files/inputs/akif_uslu/ton_Roosendaal_smooth.xml", 0, {0, 0, 0},
         "#CC79A7", ""},
        {"hw2 horse_instanced (instances, transforms)",
         "ceng795/hw2/2018S_emrebarisc/Sources/3 - Instancing, Transformation, Distribution/Scenes/horse_instanced.xml", 0,
         {0, 0, 0}, "#E69F00", ""},
    };
    return list;
}

// ---------------------------------------------------------------------------------------------
// Measuring

struct Point {
    std::size_t scene = 0, variant = 0;
    int width = 0, height = 0;
    double build_seconds = 0;
    Times cpu, wall;       // of the render, one entry per run; the chart's time is cpu's median
    double share_off = 0;  // of pixels, any channel off by more than 1/255
    double rmse = 0;       // 8-bit levels
    double median() const { return cpu.median(); }
};


[[noreturn]] void fail(const std::string& message) { throw std::runtime_error(message); }

struct Options {
    double scale = 0.5;
    int runs = 9;
    fs::path shared = PRISM_SHARED_DIR;
    fs::path output_dir = "bench/chart";
    fs::path results;       // RESULTS.md to update between the markers; empty: none
    std::string command;    // as the RESULTS.md section shows it
    std::string revision;   // git revision, as the RESULTS.md section shows it
    bool write_images = false;
};

struct SceneResult {
    std::vector<Point> points;  // one per variant, in variants() order
    std::vector<std::uint8_t> reference;
    double load_seconds = 0;
    std::size_t triangles = 0;
    int samples = 1;  // per pixel, as the scene's camera declares
};

prism::scene::Scene load_chart_scene(const ChartScene& chart_scene, const Options& options) {
    prism::scene::Scene scene = prism::io::load_scene(options.shared / chart_scene.file);
    if (chart_scene.subdivision_levels > 0) prism::scene::subdivide_largest_mesh(scene, chart_scene.subdivision_levels);
    if (chart_scene.offset != prism::scene::Vec3(0.0)) prism::scene::translate(scene, chart_scene.offset);
    // The variants are compiled with point lights alone and no per-ray features, as every hw1
    // and hw2 scene renders: a scene needing more would be refused by the renderer anyway.
    const std::string needs = prism::scene::measure_needs(scene).beyond(
        prism::Config<float, prism::Bvh<prism::Watertight>, prism::PointLightSet, prism::no_features>::meets);
    if (!needs.empty()) fail(chart_scene.name + ": the scene needs " + needs + ", and the chart's renderers have point lights only");
    if (scene.cameras.empty()) fail(chart_scene.name + ": the scene has no camera");
    return scene;
}

std::size_t triangle_count(const prism::scene::Scene& scene) {
    std::size_t count = 0;
    for (const auto& mesh : scene.meshes) count += mesh.triangles.size();
    return count;
}

SceneResult measure_scene(std::size_t scene_index, const Options& options) {
    const ChartScene& chart_scene = chart_scenes()[scene_index];
    const auto load_start = Clock::now();
    const prism::scene::Scene scene = load_chart_scene(chart_scene, options);
    SceneResult result;
    result.load_seconds = seconds_since(load_start);
    result.triangles = triangle_count(scene);
    const prism::scene::Camera& camera = scene.cameras.front();
    result.samples = std::max(1, camera.num_samples);
    const int width = prism::scaled_size(camera.width, options.scale);
    const int height = prism::scaled_size(camera.height, options.scale);
    std::cerr << chart_scene.name << ": " << result.triangles << " triangles, " << width << "x" << height
              << " pixels, " << camera.num_samples << " sample(s) per pixel (loaded in " << result.load_seconds << " s)\n";

    const std::size_t count = variants().size();
    const std::size_t reference_index = count - 1;
    std::vector<RenderFunction> renderers;
    for (std::size_t v = 0; v < count; ++v) {
        const auto start = Clock::now();
        renderers.push_back(variants()[v].build(scene));
        Point point;
        point.scene = scene_index;
        point.variant = v;
        point.build_seconds = seconds_since(start);
        result.points.push_back(point);
    }

    // Runs are interleaved: each round renders every variant once, in a new random order, so a
    // change of the machine's load falls on every variant alike. The first round is a warm-up
    // (caches, page faults, thread start-up) and gives each variant's image.
    std::vector<prism::Image> images(count);
    std::vector<std::size_t> order(count);
    std::iota(order.begin(), order.end(), 0);
    std::mt19937 shuffle(12345);
    for (int round = 0; round <= options.runs; ++round) {
        std::shuffle(order.begin(), order.end(), shuffle);
        for (const std::size_t v : order) {
            const auto start = Clock::now();
            const double cpu_start = process_cpu_seconds();
            prism::Image image = renderers[v](camera, width, height);
            const double cpu_seconds = process_cpu_seconds() - cpu_start;
            const double wall_seconds = seconds_since(start);
            if (round == 0) {
                images[v] = std::move(image);
                continue;
            }
            if (!prism::same_bits(image, images[v]))
                fail(chart_scene.name + ", " + variants()[v].name + ": run " + std::to_string(round) +
                     " rendered a different image from the first: the timing would not measure one computation");
            result.points[v].cpu.seconds.push_back(cpu_seconds);
            result.points[v].wall.seconds.push_back(wall_seconds);
        }
    }
    renderers.clear();

    // The reference again from a renderer built anew: the BVH build and the render are both
    // deterministic, or the reference is no reference.
    {
        const RenderFunction again = variants()[reference_index].build(scene);
        if (!prism::same_bits(again(camera, width, height), images[reference_index]))
            fail(chart_scene.name + ": the reference rendered by a second, separately built renderer differs");
    }

    result.reference = prism::to_8bit(images[reference_index]);
    // The reference must show the scene: at least 1% of its pixels differ from the background.
    {
        prism::Image background(1, 1);
        background.pixels[0] = glm::vec3(scene.background_color);
        const std::vector<std::uint8_t> background_bytes = prism::to_8bit(background);
        std::size_t shown = 0;
        for (std::size_t p = 0; p < result.reference.size() / 3; ++p)
            if (!std::equal(background_bytes.begin(), background_bytes.end(), result.reference.begin() + 3 * p)) ++shown;
        if (shown * 100 < result.reference.size() / 3)
            fail(chart_scene.name + ": the reference image is background almost everywhere (" + std::to_string(shown) +
                 " pixels show something)");
    }
    for (std::size_t v = 0; v < count; ++v) {
        if (images[v].width != width || images[v].height != height)
            fail(chart_scene.name + ", " + variants()[v].name + ": the image is not " + std::to_string(width) + "x" +
                 std::to_string(height));
        const std::vector<std::uint8_t> bytes = prism::to_8bit(images[v]);
        Point& point = result.points[v];
        point.width = width;
        point.height = height;
        point.share_off = prism::share_off_by_more_than(bytes, result.reference, 1);
        point.rmse = prism::rmse(bytes, result.reference);
        if (options.write_images) {
            std::string stem = std::to_string(scene_index + 1) + "_" + chart_scene.name + "_" + variants()[v].name;
            for (char& c : stem)
                if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
            prism::write_image(options.output_dir / "images" / (stem + ".png"), images[v]);
        }
        std::cerr << "  " << std::left << std::setw(46) << variants()[v].name << std::right << " build "
                  << std::setw(6) << std::fixed << std::setprecision(2) << point.build_seconds << " s, render CPU "
                  << std::setw(8) << std::setprecision(1) << 1e3 * point.median() << " ms (wall "
                  << std::setw(7) << 1e3 * point.wall.median() << " ms), off "
                  << std::setw(8) << std::setprecision(4) << 100.0 * point.share_off << "%, RMSE "
                  << std::setprecision(3) << point.rmse << std::defaultfloat << "\n";
    }
    if (result.points[reference_index].share_off != 0.0) fail(chart_scene.name + ": the reference differs from itself");
    return result;
}

// ---------------------------------------------------------------------------------------------
// The chart (SVG): render time relative to the scene's reference on x, error on a log y axis,
// one panel per error measure.

struct Panel {
    double left, top, width, height;
    std::string y_title;
    LogAxis axis;
    double (*error)(const Point&);
    bool percent;  // y values are shares, labelled in %
};

void write_svg(const fs::path& path, const std::vector<SceneResult>& results, double x_min, double x_max,
               const Options& options, const std::vector<std::string>& subtitle) {
    const std::size_t reference_index = variants().size() - 1;
    std::vector<double> shares, rmses;
    for (const auto& result : results)
        for (const auto& point : result.points) {
            shares.push_back(point.share_off);
            rmses.push_back(point.rmse);
        }
    const double width = 1180, height = 840;
    std::vector<Panel> panels{
        {90, 105, 470, 420, "pixels off by more than 1/255 (log scale)", log_axis(shares, 0.01),
         [](const Point& p) { return p.share_off; }, true},
        {670, 105, 470, 420, "RMSE, 8-bit levels (log scale)", log_axis(rmses, 1.0), [](const Point& p) { return p.rmse; },
         false},
    };
    panels[0].axis.top_decade = std::min(panels[0].axis.top_decade, 0);  // 100% at most

    std::ostringstream svg;
    svg << std::fixed << std::setprecision(1);
    svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
        << "\" viewBox=\"0 0 " << width << " " << height << "\" font-family=\"DejaVu Sans, Arial, sans-serif\">\n";
    svg << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    svg << "<text x=\"" << width / 2 << "\" y=\"32\" font-size=\"20\" text-anchor=\"middle\" font-weight=\"bold\">"
        << "prism: speed against accuracy of triangle intersectors, precision and ray offsets</text>\n";
    for (std::size_t line = 0; line < subtitle.size(); ++line)
        svg << "<text x=\"" << width / 2 << "\" y=\"" << 54 + 17 * double(line)
            << "\" font-size=\"13\" text-anchor=\"middle\">" << escape_xml(subtitle[line]) << "</text>\n";

    const auto x_of = [&](const Panel& panel, double ratio) {
        return panel.left + (ratio - x_min) / (x_max - x_min) * panel.width;
    };
    const auto y_of = [&](const Panel& panel, double value) {
        const double decade = value > 0 ? std::log10(value) : double(panel.axis.floor_decade);
        const double clamped = std::clamp(decade, double(panel.axis.floor_decade), double(panel.axis.top_decade));
        return panel.top + panel.height -
               (clamped - panel.axis.floor_decade) / double(panel.axis.top_decade - panel.axis.floor_decade) * panel.height;
    };
    // x ticks: every 0.1, 0.2 or 0.5 so that there are about six.
    double step = 0.1;
    for (const double candidate : {0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 5.0})
        if ((x_max - x_min) / candidate <= 8) {
            step = candidate;
            break;
        }
    for (const Panel& panel : panels) {
        svg << "<rect x=\"" << panel.left << "\" y=\"" << panel.top << "\" width=\"" << panel.width << "\" height=\""
            << panel.height << "\" fill=\"none\" stroke=\"#333\"/>\n";
        for (int decade = panel.axis.floor_decade; decade <= panel.axis.top_decade; ++decade) {
            const double y = y_of(panel, std::pow(10.0, decade));
            const bool zero = decade == panel.axis.floor_decade;
            svg << "<line x1=\"" << panel.left << "\" y1=\"" << y << "\" x2=\"" << panel.left + panel.width << "\" y2=\""
                << y << "\" stroke=\"" << (zero ? "#999" : "#ddd") << "\"" << (zero ? " stroke-dasharray=\"4,3\"" : "")
                << "/>\n";
            svg << "<text x=\"" << panel.left - 6 << "\" y=\"" << y + 4 << "\" font-size=\"12\" text-anchor=\"end\">"
                << (zero ? std::string("0 (exact)") : decade_label(decade, panel.percent)) << "</text>\n";
        }
        for (double tick = std::ceil(x_min / step - 1e-9) * step; tick <= x_max + 1e-9; tick += step) {
            const double x = x_of(panel, tick);
            svg << "<line x1=\"" << x << "\" y1=\"" << panel.top << "\" x2=\"" << x << "\" y2=\""
                << panel.top + panel.height << "\" stroke=\"" << (std::abs(tick - 1.0) < 1e-9 ? "#999" : "#eee")
                << "\"/>\n";
            svg << "<text x=\"" << x << "\" y=\"" << panel.top + panel.height + 18
                << "\" font-size=\"12\" text-anchor=\"middle\">" << format_number(tick, 3) << "</text>\n";
        }
        svg << "<text x=\"" << panel.left + panel.width / 2 << "\" y=\"" << panel.top + panel.height + 42
            << "\" font-size=\"13\" text-anchor=\"middle\">render CPU time / the reference's (same scene)</text>\n";
        svg << "<text transform=\"translate(" << panel.left - 62 << "," << panel.top + panel.height / 2
            << ") rotate(-90)\" font-size=\"13\" text-anchor=\"middle\">" << escape_xml(panel.y_title) << "</text>\n";
        // The reference's points last, so that the other markers do not hide the circle.
        for (std::size_t v = 0; v < variants().size(); ++v)
            for (const SceneResult& result : results) {
                const Point& point = result.points[v];
                const double ratio = point.median() / result.points[reference_index].median();
                // Every scene's reference sits at (1, 0 exact): one dark circle stands for all.
                svg << marker_svg(variants()[v].marker, x_of(panel, ratio), y_of(panel, panel.error(point)),
                                  v == reference_index ? "#222" : chart_scenes()[point.scene].colour)
                    << "\n";
            }
    }

    // Legend: marker shape = variant, colour = scene.
    const double legend_top = 600;
    svg << "<text x=\"90\" y=\"" << legend_top << "\" font-size=\"14\" font-weight=\"bold\">variant (marker)</text>\n";
    for (std::size_t v = 0; v < variants().size(); ++v) {
        const double y = legend_top + 24 + 24 * double(v);
        svg << marker_svg(variants()[v].marker, 100, y - 4, "#222") << "<text x=\"118\" y=\"" << y
            << "\" font-size=\"13\">" << escape_xml(variants()[v].name) << "</text>\n";
    }
    svg << "<text x=\"600\" y=\"" << legend_top << "\" font-size=\"14\" font-weight=\"bold\">scene (colour)</text>\n";
    for (std::size_t s = 0; s < results.size(); ++s) {
        const double y = legend_top + 24 + 24 * double(s);
        svg << "<rect x=\"603\" y=\"" << y - 11 << "\" width=\"14\" height=\"14\" fill=\"" << chart_scenes()[s].colour
            << "\"/><text x=\"626\" y=\"" << y << "\" font-size=\"13\">" << escape_xml(chart_scenes()[s].name)
            << "</text>\n";
    }
    const std::vector<std::string> notes{
        "\"0 (exact)\": no pixel differs from the reference. The reference",
        "(dark circle) is at (1, 0) for every scene, by construction.",
        "Time: median of " + std::to_string(options.runs) + " interleaved runs, process CPU time;",
        "the BVH build is not included."};
    for (std::size_t line = 0; line < notes.size(); ++line)
        svg << "<text x=\"600\" y=\"" << legend_top + 32 + 24 * double(results.size()) + 17 * double(line)
            << "\" font-size=\"12\" fill=\"#444\">" << escape_xml(notes[line]) << "</text>\n";
    svg << "</svg>\n";

    std::ofstream out(path);
    out << svg.str();
    if (!out) fail("could not write " + path.string());
}

// ---------------------------------------------------------------------------------------------
// The table (TSV and markdown) and the machine it ran on

std::string percent(double share) {
    if (share == 0.0) return "0%";
    std::ostringstream out;
    out << std::setprecision(share < 0.001 ? 2 : 3) << 100.0 * share << "%";
    return out.str();
}

void write_tsv(const fs::path& path, const std::vector<SceneResult>& results) {
    std::ofstream out(path);
    out << "scene\tvariant\twidth\theight\ttriangles\tbuild_s\trender_cpu_median_s\trender_cpu_min_s\t"
           "render_cpu_max_s\trender_wall_median_s\t"
           "time_vs_reference\tshare_off_1_255\trmse_8bit\n";
    for (const SceneResult& result : results)
        for (const Point& point : result.points)
            out << chart_scenes()[point.scene].name << '\t' << variants()[point.variant].name << '\t' << point.width
                << '\t' << point.height << '\t' << result.triangles << '\t' << point.build_seconds << '\t'
                << point.cpu.median() << '\t' << point.cpu.fastest() << '\t' << point.cpu.slowest() << '\t'
                << point.wall.median() << '\t'
                << point.median() / result.points.back().median() << '\t' << point.share_off << '\t' << point.rmse
                << '\n';
    if (!out) fail("could not write " + path.string());
}

std::string markdown_section(const std::vector<SceneResult>& results, const Options& options, double total_seconds,
                             const std::string& start_load, const std::string& date,
                             const std::vector<std::string>& checks) {
    std::string samples;
    for (const SceneResult& result : results) samples += (samples.empty() ? "" : ", ") + std::to_string(result.samples);
    std::ostringstream md;
    md << "Written by this command, run from the repository's root on " << date << ":\n\n```sh\n" << options.command
       << "\n```\n\n";
    md << "- **Machine:** `nproc` = " << std::thread::hardware_concurrency() << ", CPU `" << cpu_model()
       << "` (/proc/cpuinfo), compiler " << __VERSION__ << ", Release (`-O3 -DNDEBUG`), revision `" << options.revision
       << "`.\n";
    md << "- **Threads:** " << tbb::info::default_concurrency()
       << " (all cores; TBB tiles of 16x16 pixels). Load average before the run: " << start_load
       << "; after: " << load_average() << ".\n";
    md << "- **Scenes** (`../shared/`):";
    for (const ChartScene& chart_scene : chart_scenes()) {
        md << "\n  - " << chart_scene.name << ": `" << chart_scene.file << "`";
        if (chart_scene.subdivision_levels > 0)
            md << ", largest mesh subdivided " << chart_scene.subdivision_levels << " times (`subdivide_largest_mesh`)";
        if (chart_scene.offset != prism::scene::Vec3(0.0))
            md << ", the whole scene (camera and light too) moved by (" << chart_scene.offset.x << ", "
               << chart_scene.offset.y << ", " << chart_scene.offset.z << ") (`translate`)";
        md << (&chart_scene == &chart_scenes().back() ? "." : ";");
    }
    md << "\n";
    md << "- **Resolution:** each scene's first camera's, times `--scale " << options.scale
       << "`; the scene's own samples per pixel (" << samples << "), seed 0 for every variant.\n";
    md << "- **Time:** render only (the BVH build, wall clock, is its own column), median of " << options.runs
       << " run(s) after one warm-up; the runs are interleaved, every variant once per round in a shuffled order. "
       << "The chart's time is the process's CPU time (both threads summed), because the machine is shared and "
       << "wall-clock time also counts the other jobs holding the cores; the wall-clock median is in the table. "
       << "The program ran " << std::lround(total_seconds) << " s (loading, subdividing, BVH builds and renders; "
       << "compiling not included).\n";
    md << "- **Error:** against the reference (Watertight double, error-bound offsets) rendered from the same "
          "samples, after the course's 8-bit conversion: the share of pixels with any channel off by more than 1/255, "
          "and the RMSE over all channels in 8-bit levels. The reference's own error is 0 by construction and drawn "
          "on the \"0 (exact)\" floor of the log axes.\n";
    md << "- **Checked before writing:**";
    for (const std::string& check : checks) md << "\n  - " << check;
    md << "\n\n";
    md << "![speed against accuracy](chart/speed_accuracy.png)\n\n";
    md << "| scene | variant | build (s) | render CPU (ms): median [min, max] | render wall (ms) | CPU time / "
          "reference's | pixels off > 1/255 | RMSE (levels) |\n";
    md << "|---|---|---|---|---|---|---|---|\n";
    for (const SceneResult& result : results)
        for (const Point& point : result.points) {
            const double ratio = point.median() / result.points.back().median();
            md << "| " << chart_scenes()[point.scene].name << ", " << point.width << "x" << point.height << " | "
               << variants()[point.variant].name << " | " << std::fixed << std::setprecision(2) << point.build_seconds
               << " | " << std::setprecision(1) << 1e3 * point.cpu.median() << " [" << 1e3 * point.cpu.fastest() << ", "
               << 1e3 * point.cpu.slowest() << "] | " << 1e3 * point.wall.median() << " | " << std::setprecision(2)
               << ratio << std::defaultfloat << " | "
               << percent(point.share_off) << " | " << (point.rmse == 0.0 ? std::string("0") : format_number(point.rmse, 3))
               << " |\n";
        }
    return md.str();
}

const std::string begin_marker = "<!-- accuracy_chart:begin (written by tools/chart.sh; edits inside are overwritten) -->";
const std::string end_marker = "<!-- accuracy_chart:end -->";

void update_results(const fs::path& path, const std::string& section) {
    prism::bench::update_marked_section(path, begin_marker, end_marker, "## Speed against accuracy (tracker issue 3)",
                                        section);
}

// ---------------------------------------------------------------------------------------------

const char* usage =
    "usage: prism_accuracy_chart [--scale S] [--runs N] [--shared DIR] [--output-dir DIR] [--results RESULTS.md]\n"
    "                            [--command TEXT] [--revision TEXT] [--write-images]\n"
    "Renders the chart's scenes with every variant, compares each image with the Watertight double\n"
    "reference (error-bound offsets, same samples) and times the renders. Writes DIR/speed_accuracy.svg,\n"
    "DIR/speed_accuracy.tsv and DIR/speed_accuracy.md (the table section), and replaces the marked\n"
    "section of RESULTS.md when given. --scale: of every camera's resolution (default 0.5);\n"
    "--runs: timed runs per variant after one warm-up (default 9); --shared: the folder holding\n"
    "ceng795/ (default " PRISM_SHARED_DIR "); --write-images: every image as PNG under DIR/images.\n";

Options parse(int argc, char** argv) {
    Options options;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const auto value = [&]() -> std::string {
            if (i + 1 >= argc) fail(arg + " needs a value\n" + usage);
            return argv[++i];
        };
        if (arg == "--scale") options.scale = std::stod(value());
        else if (arg == "--runs") options.runs = std::stoi(value());
        else if (arg == "--shared") options.shared = value();
        else if (arg == "--output-dir") options.output_dir = value();
        else if (arg == "--results") options.results = value();
        else if (arg == "--command") options.command = value();
        else if (arg == "--revision") options.revision = value();
        else if (arg == "--write-images") options.write_images = true;
        else if (arg == "--help" || arg == "-h") {
            std::cout << usage;
            std::exit(0);
        } else fail("unknown option " + arg + "\n" + usage);
    }
    if (!(options.scale > 0.0 && options.scale <= 4.0)) fail("--scale must be in (0, 4]");
    if (options.runs < 1) fail("--runs must be at least 1");
    if (options.command.empty()) options.command = "prism_accuracy_chart --scale " + format_number(options.scale, 6);
    if (options.revision.empty()) options.revision = "unknown";
    return options;
}

int run(int argc, char** argv) {
    const auto start = Clock::now();
    const std::string start_load = load_average();
    const std::string date = utc_now();
    const Options options = parse(argc, argv);

    std::vector<std::pair<std::string, std::string>> files;
    for (const ChartScene& chart_scene : chart_scenes()) files.emplace_back(chart_scene.name, chart_scene.file);
    require_files(options.shared, files);
    fs::create_directories(options.output_dir);
    if (options.write_images) fs::create_directories(options.output_dir / "images");

    std::cerr << "threads: " << tbb::info::default_concurrency() << "; " << options.runs
              << " timed runs per variant; scale " << options.scale << "\n";
    std::vector<SceneResult> results;
    for (std::size_t s = 0; s < chart_scenes().size(); ++s) results.push_back(measure_scene(s, options));

    std::vector<std::string> checks{
        "every variant rendered the same image bit for bit in each of its runs;",
        "the reference rendered again by a separately built renderer is bit-identical;",
        "every image has the reference's size, and every reference shows its scene (at least 1% of its pixels "
        "are not background);"};
    for (std::size_t s = 0; s < chart_scenes().size(); ++s) {
        const std::string& other = chart_scenes()[s].same_image_as;
        if (other.empty()) continue;
        const auto match = std::find_if(chart_scenes().begin(), chart_scenes().end(),
                                        [&](const ChartScene& c) { return c.name == other; });
        const std::size_t o = std::size_t(match - chart_scenes().begin());
        // The same surface, and (moved) the same view of it: in double, 10^4 costs 2^-39 of
        // precision at most, far below a pixel.
        const double share = prism::share_off_by_more_than(results[s].reference, results[o].reference, 1);
        std::cerr << "reference of " << chart_scenes()[s].name << " against " << other << ": " << percent(share)
                  << " of pixels off by more than 1/255\n";
        if (share > 0.001)
            fail("the reference of " + chart_scenes()[s].name + " differs from that of " + other + " in " +
                 percent(share) + " of pixels (at most 0.1% allowed): they are the same surface seen the same way");
        checks.push_back("the reference of \"" + chart_scenes()[s].name + "\" matches that of \"" + other + "\": " +
                         percent(share) + " of pixels off by more than 1/255 (at most 0.1% allowed; the same surface "
                         "seen the same way);");
    }
    checks.back().back() = '.';

    double x_min = 1.0, x_max = 1.0;
    for (const SceneResult& result : results)
        for (const Point& point : result.points) {
            const double ratio = point.median() / result.points.back().median();
            x_min = std::min(x_min, ratio);
            x_max = std::max(x_max, ratio);
        }
    x_min = std::floor(x_min * 10.0 - 0.5) / 10.0;
    x_max = std::ceil(x_max * 10.0 + 0.5) / 10.0;
    const int width = results.front().points.front().width, height = results.front().points.front().height;
    const std::vector<std::string> subtitle{
        "error against Watertight double with error-bound offsets (the reference), same samples and seed; time: render "
        "CPU time, median of " + std::to_string(options.runs) + " runs",
        "resolution scale " + format_number(options.scale, 3) + " (the dragons " + std::to_string(width) + "x" +
            std::to_string(height) + "); " + std::to_string(tbb::info::default_concurrency()) + " threads; " +
            cpu_model() + "; " + date};
    write_svg(options.output_dir / "speed_accuracy.svg", results, x_min, x_max, options, subtitle);
    write_tsv(options.output_dir / "speed_accuracy.tsv", results);
    const std::string section =
        markdown_section(results, options, seconds_since(start), start_load, date, checks);
    {
        std::ofstream out(options.output_dir / "speed_accuracy.md");
        out << section;
    }
    if (!options.results.empty()) update_results(options.results, section);
    std::cerr << "wrote " << (options.output_dir / "speed_accuracy.svg").string() << ", .tsv, .md"
              << (options.results.empty() ? "" : " and the marked section of " + options.results.string()) << " in "
              << seconds_since(start) << " s\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return prism::bench::run_reporting_errors("prism_accuracy_chart", run, argc, argv); }
