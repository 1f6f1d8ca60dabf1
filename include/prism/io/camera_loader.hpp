// A scene file's cameras, in the Gaze + NearPlane form the renderer takes: lookAt cameras get
// gaze = GazePoint - Position and a symmetric near plane from FovY (the full vertical angle);
// camera transformations move Position as a point, Gaze and Up as directions. With each camera
// its <Tonemap>s (which must name distinct images), its <Renderer> and <RendererParams>, and
// <Filter>box|gaussian</Filter>, prism's own extension (default box).
#pragma once

#include <prism/image/tonemap.hpp>
#include <prism/io/element.hpp>
#include <prism/io/element_reader.hpp>
#include <prism/io/limits.hpp>
#include <prism/io/transformation_loader.hpp>
#include <prism/math/transform.hpp>
#include <prism/scene/scene.hpp>

#include <glm/glm.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace prism::io::detail::scene_loader {

class CameraLoader {
public:
    CameraLoader(ElementReader& reader, scene::Scene& scene, const TransformationLoader& transformations,
                 const ResourceLimits& limits, MemoryUse& memory)
        : reader_(reader), scene_(scene), transformations_(transformations), limits_(limits), memory_(memory) {}

    // A <Cameras> section.
    void read(const Element& section) {
        for (const Element& element : section.children) {
            if (element.name == "Camera") read_camera(element);
            else reader_.note_unsupported(element);
        }
    }

    // One <Camera>: in a <Cameras> section, or directly under <Scene> (2017).
    void read_camera(const Element& element) {
        scene::Camera camera;
        if (const std::string* id = element.attribute("id")) camera.id = std::string(trim(*id));
        const std::string* type = element.attribute("type");
        const std::string_view type_name = type != nullptr ? trim(*type) : std::string_view();
        if (!type_name.empty() && type_name != "lookAt" && type_name != "simple")
            reader_.fail(element, "unknown camera type " + in_quotes(*type) + " (expected lookAt, or none)");
        const bool look_at = type_name == "lookAt";

        camera.position = reader_.vector3(reader_.required(element, "Position"));
        camera.up = reader_.vector3(reader_.required(element, "Up"));

        const Element& resolution = reader_.required(element, "ImageResolution");
        const std::vector<long long> size = reader_.integers(resolution);
        if (size.size() != 2)
            reader_.fail(resolution, "expected 2 integers (width height), found " + std::to_string(size.size()));
        if (size[0] <= 0 || size[1] <= 0 || size[0] > std::numeric_limits<int>::max() ||
            size[1] > std::numeric_limits<int>::max())
            reader_.fail(resolution, "the image resolution must be positive, not " + std::to_string(size[0]) + " x " +
                                         std::to_string(size[1]));
        if (size[0] > max_image_side || size[1] > max_image_side || size[0] * size[1] > max_image_pixels)
            reader_.fail(resolution, std::to_string(size[0]) + " x " + std::to_string(size[1]) +
                                         " is over prism's limits, " + std::to_string(max_image_side) +
                                         " pixels a side and " + std::to_string(max_image_pixels) + " in all");
        camera.width = int(size[0]);
        camera.height = int(size[1]);
        // Every camera's film is kept until all are rendered: together with the meshes and
        // textures, within the memory limit (limits.hpp).
        memory_.film_bytes += std::uint64_t(size[0]) * std::uint64_t(size[1]) * film_bytes_per_pixel;
        if (memory_.over(limits_.memory_bytes))
            reader_.fail(resolution, "the scene's films reach " + MemoryUse::mib(memory_.film_bytes) + " here (this one " +
                                         std::to_string(size[0]) + " x " + std::to_string(size[1]) +
                                         "): " + memory_.over_message(limits_.memory_bytes));

        // The gaze is a point to look at (lookAt) or a direction. Some lookAt cameras of 2019-2022
        // give a Gaze direction instead of a GazePoint, so each form falls back on the other.
        const Element* gaze_point = element.child("GazePoint");
        const Element* gaze = element.child("Gaze");
        if (gaze_point != nullptr && (look_at || gaze == nullptr)) {
            camera.gaze = reader_.vector3(*gaze_point) - camera.position;
        } else if (gaze != nullptr) {
            camera.gaze = reader_.vector3(*gaze);
        } else {
            reader_.fail(element, look_at ? "missing <GazePoint>" : "missing <Gaze>");
        }

        // The near plane is given by its edges (NearPlane: left right bottom top) or, for lookAt
        // cameras, by the full vertical field of view FovY, centred, with the image's aspect.
        // Before 2018 NearPlane could carry a fifth number, the near distance.
        const Element* near_plane = element.child("NearPlane");
        const Element* fov = element.child("FovY");
        std::optional<double> near_distance;
        std::vector<double> plane;
        if (near_plane != nullptr && (!look_at || fov == nullptr)) {
            plane = reader_.numbers(*near_plane);
            if (plane.size() == 5) near_distance = plane[4];
            else if (plane.size() != 4)
                reader_.fail(*near_plane,
                             "expected 4 numbers (left right bottom top), found " + std::to_string(plane.size()));
        } else if (fov == nullptr) {
            reader_.fail(element, look_at ? "missing <FovY>" : "missing <NearPlane>");
        }
        if (const Element* distance = element.child("NearDistance")) {
            const double written = reader_.number(*distance);
            if (near_distance && *near_distance != written)
                reader_.fail(*distance, "the near distance differs from the fifth number of <NearPlane>");
            near_distance = written;
        }
        if (!near_distance) reader_.fail(element, "missing <NearDistance>");
        if (!(*near_distance > 0.0)) reader_.fail(element, "the near distance must be positive");
        camera.near_distance = *near_distance;
        if (!plane.empty()) {
            camera.near_left = plane[0];
            camera.near_right = plane[1];
            camera.near_bottom = plane[2];
            camera.near_top = plane[3];
        } else {
            const double fov_y = reader_.number(*fov);
            if (!(fov_y > 0.0 && fov_y < 180.0)) reader_.fail(*fov, "FovY must be between 0 and 180 degrees");
            camera.near_top = camera.near_distance * std::tan(glm::radians(fov_y) / 2.0);
            camera.near_bottom = -camera.near_top;
            camera.near_right = camera.near_top * double(camera.width) / double(camera.height);
            camera.near_left = -camera.near_right;
        }
        if (camera.near_left == camera.near_right || camera.near_bottom == camera.near_top)
            reader_.fail(plane.empty() ? *fov : *near_plane, "the near plane has no area");

        camera.image_name = reader_.text_of(reader_.required(element, "ImageName"));
        if (camera.image_name.empty()) reader_.fail(reader_.required(element, "ImageName"), "the image name is empty");
        if (const Element* e = element.child("NumSamples"))
            camera.num_samples = int(reader_.integer_within_limit(*e, 1, max_samples_per_pixel));
        if (const Element* e = element.child("ApertureSize")) camera.aperture_size = reader_.non_negative(*e);
        if (const Element* e = element.child("FocusDistance")) camera.focus_distance = reader_.non_negative(*e);
        // <Filter>box|gaussian</Filter>: prism's own extension, not a course element; box (equal
        // weights) is what the course's multisampling does.
        if (const Element* e = element.child("Filter")) {
            using enum scene::PixelFilter;
            camera.filter = reader_.keyword<scene::PixelFilter>(*e, "pixel filter", {{"box", box}, {"gaussian", gaussian}});
        }

        if (const std::string* handedness = element.attribute("handedness")) {
            const std::string_view hand = trim(*handedness);
            if (hand == "left") camera.left_handed = true;
            else if (hand != "right")
                reader_.fail(element, "handedness must be \"left\" or \"right\", not " + in_quotes(*handedness));
        }

        for (const Element& child : element.children)
            if (child.name == "Tonemap") camera.tonemaps.push_back(read_tonemap(child));
        check_tonemap_names(element, camera);
        camera.renderer = read_renderer(element);

        const glm::dmat4 transform = transformations_.transformation_of(element);
        camera.position = transform_point(transform, camera.position);
        camera.gaze = transform_direction(transform, camera.gaze);
        camera.up = transform_direction(transform, camera.up);
        if (glm::length(camera.gaze) == 0.0) reader_.fail(element, "the gaze direction is zero");
        if (glm::length(glm::cross(camera.gaze, camera.up)) == 0.0) reader_.fail(element, "Up is parallel to the gaze");

        reader_.note_unsupported_children(element, {"Position", "Gaze", "GazePoint", "Up", "NearPlane", "NearDistance",
                                                    "FovY", "ImageResolution", "ImageName", "NumSamples", "ApertureSize",
                                                    "FocusDistance", "Filter", "Transformations", "Tonemap", "Renderer",
                                                    "RendererParams"});
        scene_.cameras.push_back(std::move(camera));
    }

private:
    // <Renderer>: the course's ray tracer when absent, or PathTracing with the words of
    // <RendererParams>. A renderer prism does not implement (ProgressivePhotonMapping) is a
    // fault, never rendered as something else.
    scene::RendererParams read_renderer(const Element& camera) {
        scene::RendererParams params;
        const Element* renderer = camera.child("Renderer");
        const Element* words = camera.child("RendererParams");
        if (renderer == nullptr) {
            if (words != nullptr) reader_.fail(*words, "<RendererParams> without a <Renderer>");
            return params;
        }
        const std::string_view name = trim(renderer->text);
        if (name == "PathTracing") params.path_tracing = true;
        else if (name != "RayTracing")
            reader_.fail(*renderer, "prism does not implement the renderer " + in_quotes(std::string(name)) +
                                        " (it renders PathTracing and, without <Renderer>, the course's ray tracer)");
        if (words == nullptr) return params;
        if (!params.path_tracing) reader_.fail(*words, "<RendererParams> apply to PathTracing only");
        for (std::string_view word : split_words(words->text)) {
            if (word == "NextEventEstimation") params.next_event_estimation = true;
            else if (word == "ImportanceSampling") params.importance_sampling = true;
            else if (word == "RussianRoulette") params.russian_roulette = true;
            else if (word == "MultipleImportanceSampling") params.multiple_importance = params.next_event_estimation = true;
            else
                reader_.fail(*words, "unknown path tracing parameter " + in_quotes(std::string(word)) +
                                         " (expected NextEventEstimation, ImportanceSampling, RussianRoulette or "
                                         "MultipleImportanceSampling)");
        }
        return params;
    }

    // <Tonemap><TMO>Photographic</TMO><TMOOptions>key burn%</TMOOptions><Saturation>
    // <Gamma><Extension></Tonemap>; everything but TMO may be left out.
    scene::Tonemap read_tonemap(const Element& element) {
        scene::Tonemap tonemap;
        const Element& tmo = reader_.required(element, "TMO");
        const std::string name = reader_.text_of(tmo);
        std::string lower = name;
        std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
        if (lower == "photographic") tonemap.tone_operator = scene::TonemapOperator::photographic;
        else if (lower == "aces") tonemap.tone_operator = scene::TonemapOperator::aces;
        else if (lower == "filmic") tonemap.tone_operator = scene::TonemapOperator::filmic;
        else
            reader_.fail(tmo,
                         "unknown tone mapping operator " + in_quotes(name) + " (expected Photographic, ACES or Filmic)");
        if (const Element* options = element.child("TMOOptions")) {
            const std::vector<double> v = reader_.numbers(*options, 2);  // key, burn percentage
            if (!(v[0] > 0.0)) reader_.fail(*options, "the key value must be positive");
            if (v[1] < 0.0 || v[1] > 100.0) reader_.fail(*options, "the burn percentage must be between 0 and 100");
            tonemap.key = v[0];
            tonemap.burn_percent = v[1];
        }
        if (const Element* e = element.child("Saturation")) tonemap.saturation = reader_.non_negative(*e);
        if (const Element* e = element.child("Gamma")) {
            tonemap.gamma = reader_.number(*e);
            if (!(tonemap.gamma > 0.0)) reader_.fail(*e, "the gamma must be positive");
        }
        if (const Element* e = element.child("Extension")) {
            tonemap.extension = reader_.text_of(*e);
            const std::filesystem::path suffix(tonemap.extension);
            std::string type = suffix.extension().string();
            std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return char(std::tolower(c)); });
            if (tonemap.extension.find('/') != std::string::npos || tonemap.extension.find('\\') != std::string::npos)
                reader_.fail(*e, "the extension " + in_quotes(tonemap.extension) + " must not name a folder");
            if (!type.empty() && type != ".png" && type != ".ppm")
                reader_.fail(*e, "a tone-mapped image is 8-bit: the extension " + in_quotes(tonemap.extension) +
                                     " must end in .png or .ppm (or name no file type: .png is added)");
        }
        reader_.check_single(element, {"TMO", "TMOOptions", "Saturation", "Gamma", "Extension"});
        reader_.note_unsupported_children(element, {"TMO", "TMOOptions", "Saturation", "Gamma", "Extension"});
        return tonemap;
    }

    // Each Tonemap writes its own file (image/tonemap.hpp names them): two with the same name
    // would silently overwrite one another.
    void check_tonemap_names(const Element& camera_element, const scene::Camera& camera) const {
        std::set<std::filesystem::path> names;
        for (const scene::Tonemap& tonemap : camera.tonemaps)
            if (!names.insert(tone_mapped_image_name(camera.image_name, tonemap)).second)
                reader_.fail(camera_element, "two <Tonemap> elements write the same image " +
                                                 in_quotes(tone_mapped_image_name(camera.image_name, tonemap).string()) +
                                                 ": give them different <Extension>s");
    }

    ElementReader& reader_;
    scene::Scene& scene_;
    const TransformationLoader& transformations_;
    const ResourceLimits& limits_;
    MemoryUse& memory_;  // shared with the object and texture loaders
};

}  // namespace prism::io::detail::scene_loader
