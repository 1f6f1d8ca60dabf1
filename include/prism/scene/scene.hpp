// The plain scene description: what a scene file says, in double precision, with every id
// resolved to an index. Loaders fill it, renderers read it; it knows nothing of templates, so a
// user can also build one in code (examples/minimal) without any file format.
#pragma once

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace prism::scene {

using Vec2 = glm::dvec2;
using Vec3 = glm::dvec3;
using Mat4 = glm::dmat4;  // column-major, as GLM; applied to column vectors (p' = M p)

enum class TonemapOperator { photographic, aces, filmic };

// A camera's <Tonemap>: which curve, and the parameters the course gives it. Key and burn are
// <TMOOptions>; the burn (a percentage of pixels allowed to saturate) only shapes Photographic.
struct Tonemap {
    TonemapOperator tone_operator = TonemapOperator::photographic;
    double key = 0.18;
    double burn_percent = 0.0;
    double saturation = 1.0;
    double gamma = 2.2;
    // Appended to the stem of the camera's ImageName to name this image ("_aces.png"); empty:
    // the ImageName itself, or its stem + ".png" for an .exr ImageName.
    std::string extension;
};

// A pinhole camera in the course's "Gaze + NearPlane" form. The loader turns `type="lookAt"`
// cameras (GazePoint, FovY) and camera transformations into this form, so the renderer knows
// a single camera model.
struct Camera {
    std::string id;
    Vec3 position{0.0, 0.0, 0.0};
    Vec3 gaze{0.0, 0.0, -1.0};  // direction, not necessarily normalised
    Vec3 up{0.0, 1.0, 0.0};
    double near_left = -1.0, near_right = 1.0, near_bottom = -1.0, near_top = 1.0;
    double near_distance = 1.0;
    int width = 0, height = 0;
    std::string image_name;  // as written in the file; relative to the output folder
    // handedness="left" mirrors the image horizontally: u = gaze x up instead of up x w.
    bool left_handed = false;
    int num_samples = 1;
    double aperture_size = 0.0;
    double focus_distance = 0.0;
    // One LDR image per entry, all from the one HDR render (image/tonemap.hpp); none: a .png
    // is the course's clamp of radiance to 0..255.
    std::vector<Tonemap> tonemaps;
};

struct PointLight {
    std::string id;
    Vec3 position{0.0};
    Vec3 intensity{0.0};
};

// Parallel light from infinitely far away: Direction is the way the light travels, Radiance
// arrives undiminished at every point it reaches.
struct DirectionalLight {
    std::string id;
    Vec3 direction{0.0, -1.0, 0.0};
    Vec3 radiance{0.0};
};

// A point light restricted to a cone around Direction. Both angles are FULL apex angles in
// degrees, as the course writes them: full intensity within falloff_angle / 2 of the axis, a
// smooth decline to zero at coverage_angle / 2 (light/spot_light.hpp).
struct SpotLight {
    std::string id;
    Vec3 position{0.0};
    Vec3 direction{0.0, -1.0, 0.0};
    Vec3 intensity{0.0};
    double coverage_angle = 0.0;
    double falloff_angle = 0.0;
};

// Later topics' lights (area, environment) are added by their issues.

enum class MaterialType { blinn_phong, mirror, conductor, dielectric };

struct Material {
    std::string id;
    MaterialType type = MaterialType::blinn_phong;
    Vec3 ambient{0.0};
    Vec3 diffuse{0.0};
    Vec3 specular{0.0};
    Vec3 mirror{0.0};  // MirrorReflectance: scales the reflected ray of mirror and conductor
    double phong_exponent = 1.0;
    double refraction_index = 1.0;
    double absorption_index = 0.0;   // conductors' k in the Fresnel equations
    Vec3 absorption_coefficient{0.0};  // dielectrics' Beer's law coefficient per unit distance
    // Older schemas (2017-2019) describe glass by a Transparency colour and no type; it scales
    // the refracted ray. Zero elsewhere.
    Vec3 transparency{0.0};
    double roughness = 0.0;
    bool degamma = false;
};

enum class ShadingMode { flat, smooth };

// A triangle mesh in its own object space. Vertices are compacted per mesh: a mesh that uses
// vertices 10..20 of the global VertexData owns just those eleven, with shared vertices kept
// shared so smooth shading averages across the faces that meet there.
struct Mesh {
    std::string id;
    std::size_t material = 0;
    ShadingMode shading = ShadingMode::flat;
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;  // per vertex, optional (PLY files may carry them)
    std::vector<Vec2> uvs;      // per vertex, optional
    std::vector<std::array<std::uint32_t, 3>> triangles;
    Mat4 transform{1.0};  // object to world
};

struct Sphere {
    std::string id;
    std::size_t material = 0;
    Vec3 center{0.0};
    double radius = 1.0;
    Mat4 transform{1.0};
};

struct Plane {
    std::string id;
    std::size_t material = 0;
    Vec3 point{0.0};
    Vec3 normal{0.0, 1.0, 0.0};
    Mat4 transform{1.0};
};

// A mesh instance shares its base mesh's geometry (and its BVH); `transform` is already the
// whole object-to-world transform: with resetTransform="false" the loader composes the
// instance's transformations after the base mesh's own.
struct MeshInstance {
    std::string id;
    std::size_t base_mesh = 0;  // index into Scene::meshes
    std::size_t material = 0;
    Mat4 transform{1.0};
};

struct Scene {
    std::filesystem::path source;  // the scene file, for messages; empty for scenes built in code
    Vec3 background_color{0.0};
    double shadow_ray_epsilon = 1e-3;
    double intersection_test_epsilon = 1e-6;
    // When the element is absent: the 2025 course files leave it out yet their expected images
    // show two or more mirror bounces (bunny_with_plane); 6 is what the course's files state
    // when they state it (79 of 101).
    int max_recursion_depth = 6;
    Vec3 ambient_light{0.0};

    std::vector<Camera> cameras;
    std::vector<PointLight> point_lights;
    std::vector<DirectionalLight> directional_lights;
    std::vector<SpotLight> spot_lights;
    std::vector<Material> materials;
    std::vector<Mesh> meshes;
    std::vector<Sphere> spheres;
    std::vector<Plane> planes;
    std::vector<MeshInstance> mesh_instances;

    // Elements of the file that this version does not render (e.g. "AreaLight"), one entry per
    // distinct name, so that the renderer can say what it leaves out instead of hiding it.
    std::vector<std::string> unsupported;
};

}  // namespace prism::scene
