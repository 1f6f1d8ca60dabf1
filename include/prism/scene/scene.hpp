// The plain scene description: what a scene file says, in double precision, with every id
// resolved to an index. Loaders fill it, renderers read it; it knows nothing of templates, so a
// user can also build one in code (examples/minimal) without any file format.
#pragma once

#include <prism/image/image.hpp>
#include <prism/image/texels.hpp>

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace prism::scene {

using Vec2 = glm::dvec2;
using Vec3 = glm::dvec3;
using Mat4 = glm::dmat4;  // column-major, as GLM; applied to column vectors (p' = M p)

// How a pixel's samples are weighted: equally (box), or by a Gaussian of their distance from the
// pixel centre (standard deviation 1/2 pixel, cut off at the pixel's border).
enum class PixelFilter { box, gaussian };

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

// How a camera's image is computed: the course's recursive ray tracer, or path tracing
// (<Renderer>PathTracing</Renderer>) with the <RendererParams> the camera lists.
// multiple_importance is prism's own word (MultipleImportanceSampling), beyond the course: it
// weights next-event and BRDF samples of object lights by the power heuristic.
struct RendererParams {
    bool path_tracing = false;
    bool next_event_estimation = false;
    bool importance_sampling = false;
    bool russian_roulette = false;
    bool multiple_importance = false;
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
    // Multisampling (camera/pixel_sampler.hpp): NumSamples jittered samples per pixel, weighted
    // by the reconstruction filter.
    int num_samples = 1;
    PixelFilter filter = PixelFilter::box;
    // Thin lens: a square aperture of side ApertureSize, sharp at FocusDistance along the gaze.
    // Zero aperture: the pinhole.
    double aperture_size = 0.0;
    double focus_distance = 0.0;
    // One LDR image per entry, all from the one HDR render (image/tonemap.hpp); none: a .png
    // is the course's clamp of radiance to 0..255.
    std::vector<Tonemap> tonemaps;
    RendererParams renderer;
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

// A one-sided parallelogram emitter seen from both sides, as the course defines it: a point is
// lit through a random point of the parallelogram corner + s edge1 + t edge2 (s, t in [0, 1]).
// The 2019+ form (Position = centre, Normal, Size = side of a square, Radiance) is turned into
// this one by the loader; `radiance` is the emitted radiance in both forms (the 2017-2018
// form's Intensity is a radiance too: its irradiance is Intensity * area * cos / d^2).
struct AreaLight {
    std::string id;
    Vec3 corner{0.0};
    Vec3 edge1{1.0, 0.0, 0.0};
    Vec3 edge2{0.0, 0.0, 1.0};
    Vec3 radiance{0.0};
};

enum class EnvironmentLayout { latlong, probe };
// How an environment light picks its directions: uniformly over the hemisphere around the
// normal, cosine-weighted over it (both as the course defines them), or in proportion to the
// image's luminance (beyond the course).
enum class EnvironmentSampling { uniform, cosine, importance };

// The course's SphericalDirectionalLight: an HDR image around the scene, in lat-long or
// light-probe layout. It lights every point (sampled per shading point) and is the background
// for rays that escape.
struct EnvironmentLight {
    std::string id;
    std::size_t image = 0;  // index into Scene::images
    EnvironmentLayout layout = EnvironmentLayout::latlong;
    EnvironmentSampling sampling = EnvironmentSampling::cosine;
    Vec3 scale{1.0};  // multiplies the image's radiance
};

enum class MaterialType { blinn_phong, mirror, conductor, dielectric };

// A <BRDFs> entry (CENG795 hw6), copied into each material that names it by BRDF="id". The
// formulas are in material/brdf/.
enum class BrdfModel { original_phong, modified_phong, original_blinn_phong, modified_blinn_phong, torrance_sparrow };

struct Brdf {
    std::string id;
    BrdfModel model = BrdfModel::original_blinn_phong;
    double exponent = 1.0;    // <Exponent>
    bool normalized = false;  // the modified models' normalized="true"
    bool kdfresnel = false;   // Torrance-Sparrow's kdfresnel="true": kd (1 - F)
};

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
    // The reflectances are sRGB-encoded colours: the loader has already linearised them with
    // pow(c, 2.2) when this is set (it is kept for the record).
    bool degamma = false;
    std::optional<Brdf> brdf;  // none: the course's Blinn-Phong of hw1-hw5
};

// An image a texture or an environment light reads, decoded once by the loader into RGB as
// stored in the file (no normalisation: an 8-bit file keeps its bytes 0..255, an HDR file its
// radiance in floats; image/texels.hpp), so that bad or missing files fail at load time, naming
// the element. The decoded texels are immutable and shared, never copied: a renderer built from
// the scene (TextureSet's mip maps) holds the same texels, so a photograph is in memory once
// (VeachAjar's three JPEGs are 30 MB of bytes, which as floats were 118 MB; copying them into
// the renderer was 3% of its whole render's CPU), and a renderer may outlive the scene it was
// built from.
struct TextureImage {
    std::filesystem::path path;  // as resolved, for messages
    std::shared_ptr<const Texels> texels;
    bool high_dynamic_range = false;  // .hdr / .exr
};

enum class TextureKind { image, perlin, checkerboard };
enum class Interpolation { nearest, bilinear, trilinear };
enum class DecalMode { replace_kd, blend_kd, replace_ks, replace_background, replace_normal, bump_normal, replace_all };
// Perlin noise to a value in [0, 1]: |n| (absval, the course's "patch" look) or (n + 1) / 2
// (linear, "vein" when used with the 2019 Appearance element).
enum class NoiseConversion { absval, linear };

// One texture of the course, in either schema (2020+ <Textures><Images/><TextureMap/></Textures>
// or the older <Texture><ImageName/></Texture>): what it reads, how it is looked up, what it
// replaces. Fields unused by a kind keep their defaults.
struct Texture {
    std::string id;
    TextureKind kind = TextureKind::image;
    DecalMode decal_mode = DecalMode::replace_kd;
    // image
    std::size_t image = 0;  // index into Scene::images
    Interpolation interpolation = Interpolation::nearest;  // the course's default (texture/mipmap.hpp)
    double normalizer = 255.0;  // texel / normalizer is the value in [0, 1] (LDR images)
    bool degamma = false;       // sRGB texels: linearise (pow 2.2) after normalising
    double bump_factor = 1.0;   // scales the height for bump_normal
    // perlin
    NoiseConversion noise_conversion = NoiseConversion::absval;
    double noise_scale = 1.0;  // the point is multiplied by it before the noise is taken
    int num_octaves = 1;
    // checkerboard
    double scale = 1.0;
    double offset = 0.0;
    Vec3 black_color{0.0};
    Vec3 white_color{1.0};
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
    std::vector<std::size_t> textures;  // indices into Scene::textures, in the file's order
    Vec3 motion{0.0};  // MotionBlur: the world-space translation over the shutter interval
    // A <LightMesh>'s Radiance, emitted from both faces of every triangle (and by its
    // instances); zero for an ordinary mesh.
    Vec3 radiance{0.0};
};

struct Sphere {
    std::string id;
    std::size_t material = 0;
    Vec3 center{0.0};
    double radius = 1.0;
    Mat4 transform{1.0};
    std::vector<std::size_t> textures;
    Vec3 motion{0.0};
    Vec3 radiance{0.0};  // a <LightSphere>'s Radiance, emitted from its surface; zero otherwise
};

struct Plane {
    std::string id;
    std::size_t material = 0;
    Vec3 point{0.0};
    Vec3 normal{0.0, 1.0, 0.0};
    Mat4 transform{1.0};
    std::vector<std::size_t> textures;
};

// A mesh instance shares its base mesh's geometry (and its BVH); `transform` is already the
// whole object-to-world transform: with resetTransform="false" the loader composes the
// instance's transformations after the base mesh's own.
struct MeshInstance {
    std::string id;
    std::size_t base_mesh = 0;  // index into Scene::meshes
    std::size_t material = 0;
    Mat4 transform{1.0};
    std::vector<std::size_t> textures;  // the instance's own, else the base mesh's
    Vec3 motion{0.0};
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
    std::vector<AreaLight> area_lights;
    std::vector<EnvironmentLight> environment_lights;
    std::vector<Material> materials;
    std::vector<Mesh> meshes;
    std::vector<Sphere> spheres;
    std::vector<Plane> planes;
    std::vector<MeshInstance> mesh_instances;

    std::vector<TextureImage> images;
    std::vector<Texture> textures;
    // A texture with DecalMode replace_background: looked up at the pixel's (u, v) in [0, 1]^2
    // for primary rays that escape, instead of BackgroundColor.
    std::optional<std::size_t> background_texture;

    // Elements of the file that this version does not render (e.g. "AreaLight"), one entry per
    // distinct name, so that the renderer can say what it leaves out instead of hiding it.
    std::vector<std::string> unsupported;
};

}  // namespace prism::scene
