// prism-suite: renders a set of course scenes (a manifest, or every scene file in a folder),
// compares each camera's image with its expected image and prints one table row per image,
// so a renderer is checked against the course in one command and one exit status.
#include "../common/command_line.hpp"
#include "report.hpp"

#include <prism/image/compare.hpp>
#include <prism/image/image_io.hpp>
#include <prism/image/tonemap.hpp>
#include <prism/io/load.hpp>
#include <prism/render/progress.hpp>
#include <prism/render/render_scene.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace fs = std::filesystem;

namespace {

const prism::CommandLine command_line("prism-suite");

constexpr const char* usage = R"(usage: prism-suite (MANIFEST.tsv | FOLDER) [options]

Renders every selected scene, compares each camera's image with its expected image and prints
a table: topic, scene, format, image, size, render seconds, PSNR (dB), share of pixels off by
more than 8/255 in any channel (%), status and a note. Both images are compared as the 8-bit
values a PNG holds (radiance clamped to 0..255 and rounded). A camera with Tonemaps is compared
file by file: each tone-mapped PNG against the reference of its exact name.

MANIFEST.tsv  a tab-separated manifest with the columns topic, scene, format, path and
              references (like ceng795/MANIFEST.tsv); paths are relative to its folder;
              references are space-separated `path[confidence]` (high | medium | low). A camera
              is compared with the reference of the same file name (case and extension
              ignored; the exact extension is preferred); a scene with one camera and one
              reference pairs them whatever their names.
FOLDER        every .xml and .json scene file below FOLDER; a camera's expected image is the
              file of the camera's image name (any image extension) in `expected/` next to the
              scene, in `../expected/`, or next to the scene. Such images count as [high]. The
              topic is the first folder below FOLDER.

options:
  --topics T1,T2       only these topics (e.g. hw1,hw2)
  --scene NAME[,NAME]  only scenes of these names (the manifest's scene column, or the file
                       name without extension in folder mode)
  --format xml|json    only scene files of this format
  --scale S            render at S times the cameras' resolution (0 < S <= 1); the reference
                       is box-filtered down to the render's size before comparing
  --samples N          N samples per pixel, whatever NumSamples says (before --max-samples):
                       a reduced render (--scale) of a noisy reference needs more samples
                       per pixel to match the reference's noise in each filtered box
  --max-samples N      at most N samples per pixel, whatever NumSamples says
  --threshold DB       PSNR a judged image must reach to pass (default 40)
  --require LEVEL      high | medium | any | none: the least reference confidence that is
                       judged (default high); images with weaker references are listed as
                       `info` and never fail (none: report every PSNR, judge nothing)
  --output-dir DIR     write every render to DIR/TOPIC/SCENE-FORMAT/IMAGE_NAME
  --report DIR         also write DIR/report.html, one self-contained page (no network) with
                       the images beside it in DIR/images/: a summary and the PSNR
                       distribution, then each image's render, reference and a heat map of
                       their difference as compared, sortable by PSNR and time, filterable by
                       topic. Open it in any browser; DIR is created, and must be writable
  --threads N          worker threads (default: all hardware threads)
  --precision P        float | double-refine | double: override the precision chosen from
                       the scene
  --ray-offset M       scene-epsilon | error-bound: how rays leave surfaces (default: as
                       prism chooses from the scene)
  --seed N             seeds the sampler's numbers (default 0)
  --sampler S          independent | stratified | sobol (default: sobol)
  --cull-backfaces     camera rays ignore every triangle and plane facing away from them
  --no-cull-backfaces  camera rays see every surface from both sides (default: the course's
                       rule, back-facing triangles of every mesh; spheres and planes are
                       seen from both sides)
  --accelerator A      prism (the default) or embree (Embree 3 finds the hits; only when built
                       with libembree-dev)
  --hdr                compare radiance, and only images whose reference is HDR (.exr, .hdr):
                       both images are shown with one exposure, the one bringing the
                       reference's mean luminance to 0.18, clamped and gamma-encoded (1/2.2) to
                       8 bits; the reference is box-filtered in radiance. Other images are
                       listed as `info`. For path-traced references, whose own tone mapping
                       depends on their noise
  --verbose            print the renderer's log (configuration, build times) on stderr
  --help               this text

statuses: PASS / FAIL (PSNR against --threshold, judged references only), info (reference
below --require), rendered (no reference found), skipped (a reference no camera writes),
ERROR (the scene could not be loaded or rendered, or a judged reference could not be read or
an output not written).

The last line is the summary `N passed, M failed[, K skipped]` (FAIL and ERROR count as
failed; info, rendered and skipped as skipped).
exit status: 0 when nothing failed, 1 when something failed (or the report could not be
written at the end), 2 for usage errors (unknown option, a manifest or folder that does not
exist, a selection that matches no scene, a --report folder that cannot be created or written).
)";

std::string lowercase(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return text;
}

std::vector<std::string> split(std::string_view text, char separator) {
    std::vector<std::string> parts;
    std::size_t begin = 0;
    while (true) {
        const std::size_t end = text.find(separator, begin);
        parts.emplace_back(text.substr(begin, end == std::string_view::npos ? std::string_view::npos : end - begin));
        if (end == std::string_view::npos) return parts;
        begin = end + 1;
    }
}

// Confidence levels in the manifest's words; an unknown word ranks lowest.
int confidence_rank(std::string_view confidence) {
    if (confidence == "high") return 3;
    if (confidence == "medium") return 2;
    if (confidence == "low") return 1;
    return 0;
}

struct Arguments {
    fs::path input;
    std::vector<std::string> topics, scenes;
    std::string format;
    double threshold = 40.0;
    int required_rank = 3;
    std::optional<fs::path> output_dir;
    std::optional<fs::path> report_dir;  // --report
    bool verbose = false;
    bool hdr = false;  // --hdr
    prism::RenderOptions options;
};

Arguments parse_arguments(int argc, char** argv) {
    Arguments arguments;
    const std::vector<std::string_view> args(argv + 1, argv + argc);
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
        } else if (arg == "--topics") {
            arguments.topics = split(value(), ',');
        } else if (arg == "--scene") {
            arguments.scenes = split(value(), ',');
        } else if (arg == "--format") {
            arguments.format = lowercase(std::string(value()));
            if (arguments.format != "xml" && arguments.format != "json") command_line.usage_error("--format must be xml or json");
        } else if (arg == "--threshold") {
            arguments.threshold = command_line.number<double>(arg, value());
            if (!std::isfinite(arguments.threshold)) command_line.usage_error("--threshold must be a finite number of dB");
        } else if (arg == "--require") {
            const std::string_view level = value();
            if (level == "high") arguments.required_rank = 3;
            else if (level == "medium") arguments.required_rank = 2;
            else if (level == "any") arguments.required_rank = 0;
            else if (level == "none") arguments.required_rank = 4;  // above every confidence
            else command_line.usage_error("--require must be high, medium, any or none");
        } else if (arg == "--output-dir") {
            arguments.output_dir = fs::path(value());
        } else if (arg == "--report") {
            arguments.report_dir = fs::path(value());
        } else if (arg == "--verbose") {
            arguments.verbose = true;
        } else if (arg == "--hdr") {
            arguments.hdr = true;
        } else if (!arg.empty() && arg[0] == '-') {
            command_line.usage_error("unknown option " + std::string(arg));
        } else if (arguments.input.empty()) {
            arguments.input = fs::path(arg);
        } else {
            command_line.usage_error("more than one manifest or folder given");
        }
    }
    if (arguments.input.empty()) command_line.usage_error("no manifest or folder given");
    return arguments;
}

// ---------------------------------------------------------------------------------------------
// What to render: one Job per scene file, from a manifest row or a file found in a folder.

struct Reference {
    fs::path path;
    std::string confidence;
    int rank = 0;
};

struct Job {
    std::string topic, scene, format;
    fs::path scene_file;
    fs::path output_subfolder;        // below --output-dir, unique per job
    std::vector<Reference> references;  // manifest mode: the row's references
    bool folder_mode = false;           // folder mode: references are looked up per camera
};

// `path[confidence]` items separated by spaces; a duplicated path keeps its highest confidence.
std::vector<Reference> parse_references(const std::string& field, const fs::path& base) {
    std::vector<Reference> references;
    std::istringstream items(field);
    std::string item;
    while (items >> item) {
        Reference reference;
        const std::size_t open = item.rfind('[');
        if (open != std::string::npos && item.back() == ']') {
            reference.confidence = item.substr(open + 1, item.size() - open - 2);
            item.resize(open);
        } else {
            reference.confidence = "unknown";
        }
        reference.rank = confidence_rank(reference.confidence);
        reference.path = base / item;
        const auto same = std::find_if(references.begin(), references.end(),
                                       [&](const Reference& other) { return other.path == reference.path; });
        if (same == references.end()) references.push_back(reference);
        else if (reference.rank > same->rank) *same = reference;
    }
    return references;
}

std::vector<Job> read_manifest(const fs::path& manifest) {
    std::ifstream in(manifest);
    if (!in) command_line.usage_error(manifest.string() + ": cannot open the manifest");
    std::string line;
    std::vector<std::string> header;
    while (header.empty() && std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (!line.empty()) header = split(line, '\t');
    }
    const auto column = [&](const char* name) {
        const auto found = std::find(header.begin(), header.end(), name);
        if (found == header.end())
            command_line.usage_error(manifest.string() + ": not a manifest (no '" + name + "' column in its first line)");
        return std::size_t(found - header.begin());
    };
    const std::size_t topic = column("topic"), scene = column("scene"), format = column("format"),
                      path = column("path"), references = column("references");
    const fs::path base = manifest.parent_path();
    std::vector<Job> jobs;
    while (std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty() || line[0] == '#') continue;
        std::vector<std::string> fields = split(line, '\t');
        fields.resize(std::max(fields.size(), header.size()));  // trailing empty columns may be cut
        Job job;
        job.topic = fields[topic];
        job.scene = fields[scene];
        job.format = lowercase(fields[format]);
        job.scene_file = base / fields[path];
        job.output_subfolder = fs::path(job.topic) / (job.scene + "-" + job.format);
        job.references = parse_references(fields[references], base);
        jobs.push_back(std::move(job));
    }
    return jobs;
}

std::vector<Job> find_scenes(const fs::path& folder) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(folder, fs::directory_options::skip_permission_denied)) {
        const std::string extension = lowercase(entry.path().extension().string());
        if (entry.is_regular_file() && (extension == ".xml" || extension == ".json")) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    std::vector<Job> jobs;
    for (const fs::path& file : files) {
        const fs::path relative = file.lexically_relative(folder);
        Job job;
        job.topic = relative.has_parent_path() ? relative.begin()->string() : "-";
        job.scene = file.stem().string();
        job.format = lowercase(file.extension().string().substr(1));
        job.scene_file = file;
        job.output_subfolder = relative.parent_path() / (job.scene + "-" + job.format);
        job.folder_mode = true;
        jobs.push_back(std::move(job));
    }
    return jobs;
}

bool same_stem(const fs::path& a, const fs::path& b) {
    return lowercase(a.stem().string()) == lowercase(b.stem().string());
}
bool same_name(const fs::path& a, const fs::path& b) {
    return lowercase(a.filename().string()) == lowercase(b.filename().string());
}

bool is_image_file(const fs::path& path) {
    static const char* const extensions[] = {".png", ".exr", ".hdr", ".jpg", ".jpeg", ".bmp", ".tga", ".ppm", ".pgm"};
    const std::string extension = lowercase(path.extension().string());
    return std::any_of(std::begin(extensions), std::end(extensions), [&](const char* e) { return extension == e; });
}

// The expected image of one camera, or none.
std::optional<Reference> find_reference(const Job& job, const fs::path& image_name, std::size_t camera_count) {
    if (job.folder_mode) {
        const fs::path scene_folder = job.scene_file.parent_path();
        for (const fs::path& folder : {scene_folder / "expected", scene_folder.parent_path() / "expected", scene_folder}) {
            std::error_code error;
            if (!fs::is_directory(folder, error)) continue;
            std::optional<fs::path> found;
            for (const auto& entry : fs::directory_iterator(folder, error)) {
                if (!entry.is_regular_file() || !is_image_file(entry.path()) || !same_stem(entry.path(), image_name))
                    continue;
                if (same_name(entry.path(), image_name)) {
                    found = entry.path();
                    break;
                }
                if (!found || entry.path() < *found) found = entry.path();  // deterministic among extensions
            }
            if (found) return Reference{*found, "high", 3};
        }
        return std::nullopt;
    }
    const Reference* best = nullptr;
    const auto better = [&](const Reference& candidate) {
        if (!best) return true;
        const bool exact = same_name(candidate.path, image_name), best_exact = same_name(best->path, image_name);
        if (exact != best_exact) return exact;
        return candidate.rank > best->rank;
    };
    for (const Reference& reference : job.references)
        if (same_stem(reference.path, image_name) && better(reference)) best = &reference;
    if (!best && camera_count == 1 && job.references.size() == 1) best = &job.references.front();
    return best ? std::optional<Reference>(*best) : std::nullopt;
}

// ---------------------------------------------------------------------------------------------
// The table: rows are printed as they are finished, so a long run shows its results as it goes.

using prism::suite::Row;

struct Widths {
    std::size_t topic = 5, scene = 5, image = 5;
};

struct Tally {
    int passed = 0, failed = 0, skipped = 0;
};

std::string fixed(double value, int decimals) {
    char text[64];
    std::snprintf(text, sizeof text, "%.*f", decimals, value);
    return text;
}

std::string padded(const std::string& text, std::size_t width) {
    return text.size() >= width ? text : text + std::string(width - text.size(), ' ');
}
std::string right(const std::string& text, std::size_t width) {
    return text.size() >= width ? text : std::string(width - text.size(), ' ') + text;
}

void print_row(const Row& row, const Widths& widths) {
    std::string line = padded(row.topic, widths.topic) + "  " + padded(row.scene, widths.scene) + "  " +
                       padded(row.format, 6) + "  " + padded(row.image, widths.image) + "  " + right(row.size, 9) +
                       "  " + right(row.seconds, 9) + "  " + right(row.psnr, 8) + "  " + right(row.off, 8) + "  " +
                       padded(row.status, 8);
    if (!row.note.empty()) line += "  " + row.note;
    while (!line.empty() && line.back() == ' ') line.pop_back();
    std::cout << line << '\n' << std::flush;
}

void add_to_tally(const Row& row, Tally& tally) {
    if (row.status == "PASS") ++tally.passed;
    else if (row.status == "FAIL" || row.status == "ERROR") ++tally.failed;
    else ++tally.skipped;
}

// ---------------------------------------------------------------------------------------------

// Compares one image with its reference; `compared`, when given, receives both images as the
// comparison saw them (the report shows them so).
Row compare_image(const Arguments& arguments, const prism::scene::Camera& camera,
                  const prism::CameraImage& rendered, const Reference& reference, Row row,
                  std::optional<prism::suite::ComparedImages>* compared) {
    const bool judged = reference.rank >= arguments.required_rank;
    const auto weak = [&] { return "reference is [" + reference.confidence + "], below --require"; };
    try {
        const prism::Image expected = prism::read_image(reference.path);
        if (expected.width != camera.width || expected.height != camera.height) {
            row.status = judged ? "FAIL" : "info";
            row.note = "reference is " + std::to_string(expected.width) + "x" + std::to_string(expected.height) +
                       ", the camera " + std::to_string(camera.width) + "x" + std::to_string(camera.height);
            return row;
        }
        std::vector<std::uint8_t> expected_bytes = prism::to_8bit(expected);
        std::vector<std::uint8_t> actual = prism::to_8bit(rendered.image);
        const std::string extension = lowercase(reference.path.extension().string());
        const bool high_dynamic_range = extension == ".exr" || extension == ".hdr";
        if (arguments.hdr && !high_dynamic_range) {
            row.status = "info";
            row.note = "not an HDR reference (--hdr)";
            return row;
        }
        if (arguments.hdr) {
            const double exposure = prism::mean_grey_exposure(expected);
            expected_bytes = prism::display_8bit(
                prism::downsample_box(expected, rendered.image.width, rendered.image.height), exposure);
            actual = prism::display_8bit(rendered.image, exposure);
        } else if (rendered.image.width != expected.width || rendered.image.height != expected.height) {
            // Filter what a viewer of the full-size reference sees (its 8-bit values), not
            // radiance above 255 that the reference's PNG never held.
            prism::Image displayed(expected.width, expected.height);
            for (std::size_t i = 0; i < displayed.pixels.size(); ++i)
                displayed.pixels[i] = glm::vec3(expected_bytes[3 * i], expected_bytes[3 * i + 1], expected_bytes[3 * i + 2]);
            expected_bytes =
                prism::to_8bit(prism::downsample_box(displayed, rendered.image.width, rendered.image.height));
        }
        if (compared) *compared = prism::suite::ComparedImages{rendered.image.width, rendered.image.height, actual, expected_bytes};
        const double psnr = prism::psnr(actual, expected_bytes);
        row.psnr = std::isinf(psnr) ? "inf" : fixed(psnr, 2);
        row.off = fixed(100.0 * prism::share_off_by_more_than(actual, expected_bytes, 8), 2);
        if (!judged) {
            row.status = "info";
            row.note = weak();
        } else {
            row.status = psnr >= arguments.threshold ? "PASS" : "FAIL";
        }
    } catch (const std::exception& error) {
        row.status = judged ? "ERROR" : "info";
        row.note = error.what();
    }
    return row;
}

// Loads, renders and compares one scene; prints its rows and adds them to the tally.
void run_job(const Arguments& arguments, const Job& job, std::size_t index, std::size_t job_count,
             const Widths& widths, Tally& tally, prism::suite::Report* report) {
    Row scene_row;
    scene_row.topic = job.topic;
    scene_row.scene = job.scene;
    scene_row.format = job.format;
    const auto emit = [&](const Row& row, const std::optional<prism::suite::ComparedImages>& images = std::nullopt) {
        print_row(row, widths);
        add_to_tally(row, tally);
        if (report) report->add(row, images);
    };
    std::ostringstream log;
    try {
        const prism::scene::Scene scene = prism::io::load_scene(job.scene_file);
        if (scene.cameras.empty())
            throw prism::io::LoadError(job.scene_file, "<Cameras>", "the scene has no camera");

        const std::size_t total_pixels = prism::total_pixels(scene, arguments.options);
        std::vector<prism::CameraImage> images;
        {
            prism::ProgressBar progress(total_pixels, true,
                                        "[" + std::to_string(index + 1) + "/" + std::to_string(job_count) + "] " +
                                            job.scene + "." + job.format);
            images = prism::render_scene(scene, arguments.options, log,
                                         [&](std::size_t, int pixels) { progress.advance(std::size_t(pixels)); });
        }
        if (arguments.verbose) std::cerr << job.scene_file.string() << ":\n" << log.str();

        std::string unsupported;
        for (const auto& name : scene.unsupported) unsupported += (unsupported.empty() ? "" : " ") + name;
        std::vector<bool> reference_used(job.references.size(), false);
        for (const prism::CameraImage& rendered : images) {
            const prism::scene::Camera& camera = scene.cameras[rendered.camera];
            // Every file the camera writes is compared: the raw image, and each Tonemap's PNG
            // (tone-mapped from the same render, as `prism` writes them).
            std::vector<prism::CameraOutput> outputs = prism::camera_outputs(camera);
            if (rendered.image_name.empty()) outputs = {{fs::path("camera_" + camera.id + ".png"), std::nullopt}};
            for (const prism::CameraOutput& output : outputs) {
                const fs::path image_name = output.name.filename();
                prism::CameraImage shown = rendered;
                if (output.tonemap) shown.image = prism::tone_map(rendered.image, camera.tonemaps[*output.tonemap]);
                Row row = scene_row;
                std::optional<prism::suite::ComparedImages> compared;
                row.image = image_name.string();
                row.size = std::to_string(shown.image.width) + "x" + std::to_string(shown.image.height);
                row.seconds = fixed(rendered.seconds, 2);
                std::optional<Reference> reference = find_reference(job, image_name, scene.cameras.size());
                // A camera writing several files pairs each with the reference of its exact
                // name: latlong.exr must not be judged against latlong.png's tone mapping.
                if (reference && outputs.size() > 1 && !same_name(reference->path, image_name)) reference.reset();
                if (reference) {
                    for (std::size_t r = 0; r < job.references.size(); ++r)
                        if (job.references[r].path == reference->path || same_stem(job.references[r].path, image_name))
                            reference_used[r] = true;
                    row = compare_image(arguments, camera, shown, *reference, row, report ? &compared : nullptr);
                } else {
                    row.status = "rendered";
                }
                if (arguments.output_dir) {
                    const fs::path written = *arguments.output_dir / job.output_subfolder / image_name;
                    std::error_code error;
                    if (reference && fs::equivalent(written, reference->path, error)) {
                        row.note += std::string(row.note.empty() ? "" : "; ") + "not written over its reference";
                    } else {
                        try {
                            prism::write_image(written, shown.image);
                        } catch (const std::exception& write_error) {
                            row.status = "ERROR";
                            row.note += std::string(row.note.empty() ? "" : "; ") + write_error.what();
                        }
                    }
                }
                if (!unsupported.empty())
                    row.note += std::string(row.note.empty() ? "" : "; ") + "not rendered yet: " + unsupported;
                // A row compared with nothing still shows its render, clamped to 8 bits.
                if (report && !compared)
                    compared = prism::suite::ComparedImages{shown.image.width, shown.image.height, prism::to_8bit(shown.image), {}};
                emit(row, compared);
            }
        }
        for (std::size_t r = 0; r < job.references.size(); ++r)
            if (!reference_used[r]) {
                Row row = scene_row;
                row.image = job.references[r].path.filename().string();
                row.status = "skipped";
                row.note = "no camera writes this reference's image";
                emit(row);
            }
    } catch (const std::exception& error) {
        if (arguments.verbose) std::cerr << job.scene_file.string() << ":\n" << log.str();
        Row row = scene_row;
        row.status = "ERROR";
        row.note = error.what();
        emit(row);
    }
}

bool selected(const std::vector<std::string>& allowed, const std::string& value) {
    return allowed.empty() || std::find(allowed.begin(), allowed.end(), value) != allowed.end();
}

}  // namespace

int main(int argc, char** argv) {
    const Arguments arguments = parse_arguments(argc, argv);
    std::error_code error;
    if (!fs::exists(arguments.input, error)) command_line.usage_error(arguments.input.string() + ": no such manifest or folder");

    std::vector<Job> jobs;
    try {
        jobs = fs::is_directory(arguments.input) ? find_scenes(arguments.input) : read_manifest(arguments.input);
    } catch (const fs::filesystem_error& listing_error) {
        command_line.usage_error(listing_error.what());
    }
    std::erase_if(jobs, [&](const Job& job) {
        return !selected(arguments.topics, job.topic) || !selected(arguments.scenes, job.scene) ||
               (!arguments.format.empty() && job.format != arguments.format);
    });
    if (jobs.empty()) command_line.usage_error(arguments.input.string() + ": no scene matches the selection");

    // Widths from what is known before rendering; an unexpectedly long image name only widens its
    // own row.
    Widths widths;
    for (const Job& job : jobs) {
        widths.topic = std::max(widths.topic, job.topic.size());
        widths.scene = std::max(widths.scene, job.scene.size());
        widths.image = std::max(widths.image, job.scene.size() + 4);
        for (const Reference& reference : job.references)
            widths.image = std::max(widths.image, reference.path.filename().string().size());
    }
    const char* judged = arguments.required_rank == 4   ? "no"
                         : arguments.required_rank == 3 ? "[high]"
                         : arguments.required_rank == 2 ? "[high] and [medium]"
                                                        : "all";
    std::ostringstream heading;
    heading << "prism-suite: " << jobs.size() << (jobs.size() == 1 ? " scene" : " scenes") << " from "
            << arguments.input.string() << "; PASS: PSNR >= " << arguments.threshold << " dB against " << judged
            << " references; scale " << arguments.options.resolution_scale;

    // The report's folder is checked before anything renders: a long run must not end unable to
    // write its page.
    std::optional<prism::suite::Report> report;
    if (arguments.report_dir) {
        try {
            report.emplace(*arguments.report_dir);
        } catch (const std::exception& report_error) {
            std::cerr << "prism-suite: " << report_error.what() << '\n';
            return 2;
        }
    }

    std::cout << heading.str() << "\n\n";
    print_row({"topic", "scene", "format", "image", "size", "seconds", "PSNR(dB)", "off>8(%)", "status", "note"},
              widths);

    Tally tally;
    for (std::size_t i = 0; i < jobs.size(); ++i)
        run_job(arguments, jobs[i], i, jobs.size(), widths, tally, report ? &*report : nullptr);

    std::cout << '\n' << tally.passed << " passed, " << tally.failed << " failed";
    if (tally.skipped > 0) std::cout << ", " << tally.skipped << " skipped";
    std::cout << '\n';
    if (report) {
        try {
            report->write(heading.str());
            std::cout << "report: " << report->page().string() << '\n';
        } catch (const std::exception& report_error) {
            std::cerr << "prism-suite: " << report_error.what() << '\n';
            return 1;
        }
    }
    return tally.failed > 0 ? 1 : 0;
}
