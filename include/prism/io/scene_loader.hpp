// The one interpreter of CENG795 scene files (all schema years, XML and JSON alike): element tree
// -> scene::Scene, with every id resolved and every fault reported as a LoadError naming the
// element. Each section has its reader beside this file: transformation_loader.hpp,
// material_loader.hpp (with brdf_loader.hpp), texture_loader.hpp, camera_loader.hpp,
// light_loader.hpp, vertex_data_loader.hpp and object_loader.hpp. Conventions it settles for
// the renderer:
//   - Transformations are applied in the order written: `r1 t3` is first r1, then t3 (M = T3 R1).
//   - Cameras come out in the Gaze + NearPlane form: lookAt cameras get gaze = GazePoint - Position
//     and a symmetric near plane from FovY (the full vertical angle); camera transformations move
//     Position as a point, Gaze and Up as directions.
//   - Mesh instances carry their whole transform (the instance's own, after the base mesh's unless
//     resetTransform="true") and their material (their own, else the base's).
//   - SpotLight angles are full apex angles in degrees; DirectionalLight's Direction is the way the
//     light travels. A camera's Tonemaps must name distinct images.
//   - Textures, images and the background texture: texture_loader.hpp (both schemas; an older
//     schema's bumpmap="true" texture becomes its DecalMode texture plus a bump_normal one).
//   - AreaLight: the 2019+ square (centre, Normal, Size) becomes corner + two edges, the course's
//     orthonormal pair around the normal (light_loader.hpp); the 2017-2018 corner + EdgeVectors
//     form is taken as written, its Intensity (the whole panel's) as radiance Intensity / area.
//   - MotionBlur on Mesh, Triangle, Sphere and MeshInstance (the instance's own, else none);
//     an instance's textures are its own, else its base mesh's.
//   - degamma="true" materials get Ambient/Diffuse/SpecularReflectance linearised by pow(c, 2.2).
//   - A camera's <Filter>box|gaussian</Filter> is prism's own extension (default box).
//   - Elements of later topics are skipped and named once each in Scene::unsupported.
#pragma once

#include <prism/io/brdf_loader.hpp>
#include <prism/io/camera_loader.hpp>
#include <prism/io/element.hpp>
#include <prism/io/element_reader.hpp>
#include <prism/io/light_loader.hpp>
#include <prism/io/limits.hpp>
#include <prism/io/load_error.hpp>
#include <prism/io/load_options.hpp>
#include <prism/io/material_loader.hpp>
#include <prism/io/object_loader.hpp>
#include <prism/io/texture_loader.hpp>
#include <prism/io/transformation_loader.hpp>
#include <prism/io/vertex_data_loader.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <filesystem>
#include <string>
#include <utility>

namespace prism::io {

namespace detail::scene_loader {

class Interpreter : private ElementReader {
public:
    Interpreter(const std::filesystem::path& file, const LoadOptions& options) : ElementReader(file), options_(options) {}

    scene::Scene interpret(const Element& root) {
        if (root.name != "Scene") fail(root, "the root element must be <Scene>, not <" + root.name + ">");
        scene_.source = file_;
        // Definitions first, wherever the file puts them: objects and cameras refer to them.
        check_single(root, {"BackgroundColor", "ShadowRayEpsilon", "IntersectionTestEpsilon", "MaxRecursionDepth",
                            "VertexData", "TexCoordData"});
        for (const Element& child : root.children)
            if (child.name == "BRDFs") brdfs_.read(child);  // before the materials that name them
        for (const Element& child : root.children) {
            if (child.name == "VertexData") vertex_data_.read_vertex_data(child);
            else if (child.name == "TexCoordData") vertex_data_.read_texture_coordinates(child);
            else if (child.name == "Transformations") transformations_.read(child);
            else if (child.name == "Materials") materials_.read(child);
            else if (child.name == "Textures") textures_.read(child);
        }
        for (const Element& child : root.children) {
            const std::string& name = child.name;
            if (name == "BackgroundColor") scene_.background_color = vector3(child);
            else if (name == "ShadowRayEpsilon") scene_.shadow_ray_epsilon = non_negative(child);
            else if (name == "IntersectionTestEpsilon") scene_.intersection_test_epsilon = non_negative(child);
            else if (name == "MaxRecursionDepth") scene_.max_recursion_depth = int(integer_within_limit(
                child, 0, std::min(options_.limits.max_recursion_depth, stack_safe_recursion_depth),
                "--max-recursion-depth raises it up to " + std::to_string(stack_safe_recursion_depth)));
            else if (name == "Camera") cameras_.read_camera(child);  // 2017: cameras directly under <Scene>
            else if (name == "Cameras") cameras_.read(child);
            else if (name == "Lights") lights_.read(child);
            else if (name == "Objects") objects_.read(child);
            else if (name != "VertexData" && name != "TexCoordData" && name != "Transformations" && name != "Materials" &&
                     name != "Textures" && name != "BRDFs")
                note_unsupported(child);
        }
        scene_.unsupported = take_unsupported();
        return std::move(scene_);
    }

private:
    LoadOptions options_;
    scene::Scene scene_;
    MemoryUse memory_;  // what the meshes and images read so far will take (limits.hpp)
    TextureLoader textures_{*this, scene_, options_.limits, memory_};
    BrdfLoader brdfs_{*this};
    TransformationLoader transformations_{*this};
    MaterialLoader materials_{*this, scene_, brdfs_, options_.untyped_mirrors_reflect};
    CameraLoader cameras_{*this, scene_, transformations_, options_.limits, memory_};
    LightLoader lights_{*this, scene_, transformations_, textures_};
    VertexDataLoader vertex_data_{*this};
    ObjectLoader objects_{*this, scene_, options_.limits, memory_, transformations_, materials_, textures_, vertex_data_};
};

}  // namespace detail::scene_loader

// Interprets a scene file's element tree; `file` names the file in messages and locates PLYs.
inline scene::Scene interpret_scene(const Element& root, const std::filesystem::path& file,
                                    const LoadOptions& options = {}) {
    return detail::scene_loader::Interpreter(file, options).interpret(root);
}

}  // namespace prism::io
