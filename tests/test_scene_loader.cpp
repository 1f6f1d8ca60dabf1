// Scene loading: every course scene of the manifest, each XML scene against its JSON twin,
// hand-checked scenes (camera, lookAt near plane, transformations, instances), and one test per
// kind of broken input, each of which must name the file and the element at fault.
#include "course_manifest.hpp"
#include "temporary_folder.hpp"
#include "text_contains.hpp"

#include <prism/io/load.hpp>
#include <prism/math/transform.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

using prism_test::contains;

namespace {

namespace fs = std::filesystem;
using prism::io::LoadError;
using prism::io::load_scene;
using prism::scene::Scene;
using Vec3 = prism::scene::Vec3;

using prism_test::course_folder;
using prism_test::ManifestRow;
using prism_test::read_manifest;

// Manifest files that cannot load as published. Each must keep failing with its message, so a
// loader change that silently accepts the fault is noticed.
struct KnownBroken {
    std::string_view path;
    std::string_view message;
    std::string_view why;
};
constexpr KnownBroken known_broken[] = {
    {"hw7_pathtracing_objlights/2019S_EgeCiklabakkal/inputs/project/cornellbox_jaroslav_diffuse.xml",
     "does not implement the renderer \"ProgressivePhotonMapping\"",
     "its camera asks for progressive photon mapping, which prism refuses rather than render as something else"},
    {"hw7_pathtracing_objlights/2019S_EgeCiklabakkal/inputs/project/cornellbox_jaroslav_glass.xml",
     "does not implement the renderer \"ProgressivePhotonMapping\"",
     "its camera asks for progressive photon mapping, which prism refuses rather than render as something else"},
    {"hw2/2018S_emrebarisc/Sources/3 - Instancing, Transformation, Distribution/Scenes/instanced_bunny.xml",
     "already defined",
     "two <Translation id=\"1\">, and references to t2, t3 and material 3, which no element defines"},
    {"hw4/2019S_EgeCiklabakkal/inputs/hw4/bump_mapping_basic.xml", "no such image file",
     "its textures/ folder was not published with the scene"},
    {"hw4/2019S_EgeCiklabakkal/inputs/hw4/bump_mapping_basic_nobump.xml", "no such image file",
     "its textures/ folder was not published with the scene"},
    {"hw4/2019S_EgeCiklabakkal/inputs/hw4/bump_mapping_transformed_nobump.xml", "no such image file",
     "its textures/ folder was not published with the scene"},
    {"hw4/2019S_EgeCiklabakkal/inputs/hw4/sphere_bump_nobump.xml", "no such image file",
     "its textures/ folder was not published with the scene"},
    {"hw4/2019S_EgeCiklabakkal/inputs/hw4/sphere_texture_blend_bilinear.xml", "no such image file",
     "its textures/ folder was not published with the scene"},
    {"hw4/2019S_EgeCiklabakkal/inputs/hw4/sphere_texture_replace_bilinear.xml", "no such image file",
     "its textures/ folder was not published with the scene"},
    {"hw4/2019S_EgeCiklabakkal/inputs/hw4/sphere_texture_replace_nearest.xml", "no such image file",
     "its textures/ folder was not published with the scene"},
};

const KnownBroken* find_known_broken(std::string_view path) {
    for (const KnownBroken& broken : known_broken)
        if (broken.path == path) return &broken;
    return nullptr;
}

// Runs `load` and returns the LoadError's message, or "" (with a failed check) when none is thrown.
template <class Load>
std::string load_error_of(Load&& load) {
    try {
        load();
    } catch (const LoadError& error) {
        return error.what();
    }
    FAIL_CHECK("no LoadError was thrown");
    return {};
}

// XML/JSON twins that differ in the files themselves (the 2025 JSON editions were revised), with
// the differences compare_scenes must report: nothing more, nothing less.
const std::map<std::string, std::vector<std::string>> known_twin_differences = {
    // The JSON's dielectric material 6 has MirrorReflectance 1 1 1; the XML's has none.
    {"hw1/cornellbox_recursive",
     {"material 6 mirror[0]: 0 against 1", "material 6 mirror[1]: 0 against 1", "material 6 mirror[2]: 0 against 1"}},
    // The same for the JSON's dielectric material 3.
    {"hw1/scienceTree_glass",
     {"material 3 mirror[0]: 0 against 1", "material 3 mirror[1]: 0 against 1", "material 3 mirror[2]: 0 against 1"}},
    // The JSON adds a ninth vertex and a Plane on it.
    {"hw1/simple", {"planes: 0 against 1"}},
};

// ---- comparing two scenes -------------------------------------------------------------------

class Differences {
public:
    explicit Differences(double tolerance) : tolerance_(tolerance) {}

    void number(const std::string& what, double a, double b) {
        if (!(std::abs(a - b) <= tolerance_ * std::max(1.0, std::abs(a)))) add(what, a, b);
    }
    void vector(const std::string& what, const Vec3& a, const Vec3& b) {
        for (int i = 0; i < 3; ++i) number(what + "[" + std::to_string(i) + "]", a[i], b[i]);
    }
    void matrix(const std::string& what, const glm::dmat4& a, const glm::dmat4& b) {
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) number(what + "[" + std::to_string(c) + "][" + std::to_string(r) + "]", a[c][r], b[c][r]);
    }
    template <class T>
    void same(const std::string& what, const T& a, const T& b) {
        if (!(a == b)) list_.push_back(what + " differs");
    }
    bool count(const std::string& what, std::size_t a, std::size_t b) {
        if (a != b) list_.push_back(what + ": " + std::to_string(a) + " against " + std::to_string(b));
        return a == b;
    }
    const std::vector<std::string>& list() const { return list_; }

private:
    void add(const std::string& what, double a, double b) {
        std::ostringstream out;
        out.precision(17);
        out << what << ": " << a << " against " << b;
        list_.push_back(out.str());
    }
    double tolerance_;
    std::vector<std::string> list_;
};

std::vector<std::string> compare_scenes(const Scene& a, const Scene& b) {
    Differences d(1e-12);
    d.vector("background", a.background_color, b.background_color);
    d.number("shadow ray epsilon", a.shadow_ray_epsilon, b.shadow_ray_epsilon);
    d.number("intersection test epsilon", a.intersection_test_epsilon, b.intersection_test_epsilon);
    d.same("max recursion depth", a.max_recursion_depth, b.max_recursion_depth);
    d.vector("ambient light", a.ambient_light, b.ambient_light);
    if (d.count("cameras", a.cameras.size(), b.cameras.size()))
        for (std::size_t i = 0; i < a.cameras.size(); ++i) {
            const auto &x = a.cameras[i], &y = b.cameras[i];
            const std::string name = "camera " + std::to_string(i);
            d.vector(name + " position", x.position, y.position);
            d.vector(name + " gaze", x.gaze, y.gaze);
            d.vector(name + " up", x.up, y.up);
            d.number(name + " near left", x.near_left, y.near_left);
            d.number(name + " near right", x.near_right, y.near_right);
            d.number(name + " near bottom", x.near_bottom, y.near_bottom);
            d.number(name + " near top", x.near_top, y.near_top);
            d.number(name + " near distance", x.near_distance, y.near_distance);
            d.same(name + " width", x.width, y.width);
            d.same(name + " height", x.height, y.height);
            d.same(name + " image name", x.image_name, y.image_name);
            d.same(name + " handedness", x.left_handed, y.left_handed);
            d.same(name + " samples", x.num_samples, y.num_samples);
        }
    if (d.count("point lights", a.point_lights.size(), b.point_lights.size()))
        for (std::size_t i = 0; i < a.point_lights.size(); ++i) {
            d.vector("light " + std::to_string(i) + " position", a.point_lights[i].position, b.point_lights[i].position);
            d.vector("light " + std::to_string(i) + " intensity", a.point_lights[i].intensity, b.point_lights[i].intensity);
        }
    if (d.count("materials", a.materials.size(), b.materials.size()))
        for (std::size_t i = 0; i < a.materials.size(); ++i) {
            const auto &x = a.materials[i], &y = b.materials[i];
            const std::string name = "material " + x.id;
            d.same(name + " type", x.type, y.type);
            d.vector(name + " ambient", x.ambient, y.ambient);
            d.vector(name + " diffuse", x.diffuse, y.diffuse);
            d.vector(name + " specular", x.specular, y.specular);
            d.vector(name + " mirror", x.mirror, y.mirror);
            d.number(name + " phong exponent", x.phong_exponent, y.phong_exponent);
            d.number(name + " refraction index", x.refraction_index, y.refraction_index);
            d.number(name + " absorption index", x.absorption_index, y.absorption_index);
            d.vector(name + " absorption coefficient", x.absorption_coefficient, y.absorption_coefficient);
            d.vector(name + " transparency", x.transparency, y.transparency);
            d.number(name + " roughness", x.roughness, y.roughness);
            d.same(name + " degamma", x.degamma, y.degamma);
        }
    if (d.count("meshes", a.meshes.size(), b.meshes.size()))
        for (std::size_t i = 0; i < a.meshes.size(); ++i) {
            const auto &x = a.meshes[i], &y = b.meshes[i];
            const std::string name = "mesh " + std::to_string(i);
            d.same(name + " material", x.material, y.material);
            d.same(name + " shading", x.shading, y.shading);
            d.same(name + " triangles", x.triangles, y.triangles);
            d.matrix(name + " transform", x.transform, y.transform);
            if (d.count(name + " positions", x.positions.size(), y.positions.size()))
                for (std::size_t v = 0; v < x.positions.size(); ++v)
                    d.vector(name + " position " + std::to_string(v), x.positions[v], y.positions[v]);
            d.count(name + " normals", x.normals.size(), y.normals.size());
            d.count(name + " uvs", x.uvs.size(), y.uvs.size());
        }
    if (d.count("spheres", a.spheres.size(), b.spheres.size()))
        for (std::size_t i = 0; i < a.spheres.size(); ++i) {
            const std::string name = "sphere " + std::to_string(i);
            d.same(name + " material", a.spheres[i].material, b.spheres[i].material);
            d.vector(name + " center", a.spheres[i].center, b.spheres[i].center);
            d.number(name + " radius", a.spheres[i].radius, b.spheres[i].radius);
            d.matrix(name + " transform", a.spheres[i].transform, b.spheres[i].transform);
        }
    if (d.count("planes", a.planes.size(), b.planes.size()))
        for (std::size_t i = 0; i < a.planes.size(); ++i) {
            const std::string name = "plane " + std::to_string(i);
            d.same(name + " material", a.planes[i].material, b.planes[i].material);
            d.vector(name + " point", a.planes[i].point, b.planes[i].point);
            d.vector(name + " normal", a.planes[i].normal, b.planes[i].normal);
            d.matrix(name + " transform", a.planes[i].transform, b.planes[i].transform);
        }
    if (d.count("mesh instances", a.mesh_instances.size(), b.mesh_instances.size()))
        for (std::size_t i = 0; i < a.mesh_instances.size(); ++i) {
            const std::string name = "instance " + std::to_string(i);
            d.same(name + " base mesh", a.mesh_instances[i].base_mesh, b.mesh_instances[i].base_mesh);
            d.same(name + " material", a.mesh_instances[i].material, b.mesh_instances[i].material);
            d.matrix(name + " transform", a.mesh_instances[i].transform, b.mesh_instances[i].transform);
        }
    return d.list();
}

// ---- scenes written by the tests ------------------------------------------------------------

using prism_test::TemporaryFolder;

struct SceneParts {
    std::string camera = R"(<Camera id="1">
            <Position>0 0 0</Position>
            <Gaze>0 0 -1</Gaze>
            <Up>0 1 0</Up>
            <NearPlane>-1 1 -1 1</NearPlane>
            <NearDistance>1</NearDistance>
            <ImageResolution>16 16</ImageResolution>
            <ImageName>out.png</ImageName>
        </Camera>)";
    std::string transformations;
    std::string vertices = "-0.5 0.5 -2\n -0.5 -0.5 -2\n 0.5 -0.5 -2\n";
    std::string objects = "<Mesh id=\"1\"><Material>1</Material><Faces>1 2 3</Faces></Mesh>";
};

std::string scene_xml(const SceneParts& parts) {
    return R"(<Scene>
    <Cameras>
        )" + parts.camera + R"(
    </Cameras>
    <Lights>
        <AmbientLight>25 25 25</AmbientLight>
        <PointLight id="1"><Position>0 0 0</Position><Intensity>1000 1000 1000</Intensity></PointLight>
    </Lights>
    <Materials>
        <Material id="1">
            <AmbientReflectance>1 1 1</AmbientReflectance>
            <DiffuseReflectance>1 1 1</DiffuseReflectance>
            <SpecularReflectance>1 1 1</SpecularReflectance>
        </Material>
        <Material id="2" type="mirror">
            <MirrorReflectance>1 1 1</MirrorReflectance>
        </Material>
    </Materials>
    <Transformations>
        )" + parts.transformations + R"(
    </Transformations>
    <VertexData>
        )" + parts.vertices + R"(
    </VertexData>
    <Objects>
        )" + parts.objects + R"(
    </Objects>
</Scene>
)";
}

bool near(const Vec3& a, const Vec3& b, double tolerance = 1e-12) {
    return glm::all(glm::lessThanEqual(glm::abs(a - b), Vec3(tolerance)));
}

bool near(const glm::dmat4& a, const glm::dmat4& b, double tolerance = 1e-12) {
    for (int c = 0; c < 4; ++c)
        if (!near(Vec3(a[c]), Vec3(b[c]), tolerance) || std::abs(a[c][3] - b[c][3]) > tolerance) return false;
    return true;
}

// Checks that loading `scene` throws a LoadError whose message names the scene file and whose
// element is `element`'s; returns the message for further checks.
std::string check_load_error(const fs::path& scene, std::string_view element) {
    std::string message;
    try {
        load_scene(scene);
        FAIL_CHECK("no LoadError for " << scene);
    } catch (const LoadError& error) {
        message = error.what();
        INFO(message);
        CHECK(contains(message, scene.filename().string()));
        CHECK(error.file() == scene);
        CHECK(contains(error.element(), element));
    }
    return message;
}

}  // namespace

// ---- the course's scenes --------------------------------------------------------------------

TEST_CASE("every course scene of the manifest loads") {
    if (!fs::exists(course_folder / "MANIFEST.tsv")) {
        MESSAGE("skipped: no " << (course_folder / "MANIFEST.tsv"));
        return;
    }
    const std::vector<ManifestRow> rows = read_manifest();
    REQUIRE(!rows.empty());
    std::size_t loaded = 0;
    for (const ManifestRow& row : rows) {
        INFO(row.path);
        if (!row.unresolved.empty()) {
            MESSAGE("not loaded, its assets are unresolved (" << row.unresolved << "): " << row.path);
            continue;
        }
        const fs::path file = course_folder / row.path;
        if (const KnownBroken* broken = find_known_broken(row.path)) {
            const std::string message = load_error_of([&] { load_scene(file); });
            CHECK(contains(message, broken->message));
            MESSAGE("known broken, fails as expected (" << broken->why << "): " << message);
            continue;
        }
        try {
            const Scene scene = load_scene(file);
            CHECK(!scene.cameras.empty());
            CHECK(scene.meshes.size() + scene.spheres.size() + scene.planes.size() + scene.mesh_instances.size() > 0);
            ++loaded;
        } catch (const std::exception& error) {
            FAIL_CHECK(error.what());
        }
    }
    MESSAGE(loaded << " of " << rows.size() << " manifest scene files loaded");
}

TEST_CASE("scenes given in both XML and JSON describe the same scene") {
    if (!fs::exists(course_folder / "MANIFEST.tsv")) {
        MESSAGE("skipped: no " << (course_folder / "MANIFEST.tsv"));
        return;
    }
    std::map<std::string, std::map<std::string, std::string>> by_scene;  // topic/scene -> format -> path
    for (const ManifestRow& row : read_manifest())
        if (row.unresolved.empty() && find_known_broken(row.path) == nullptr)
            by_scene[row.topic + "/" + row.scene][row.format] = row.path;
    std::size_t pairs = 0;
    for (const auto& scene_files : by_scene) {
        const std::string& name = scene_files.first;
        const auto& formats = scene_files.second;
        if (formats.count("xml") == 0 || formats.count("json") == 0) continue;
        ++pairs;
        INFO(name << ": " << formats.at("xml") << " against " << formats.at("json"));
        try {
            const Scene xml = load_scene(course_folder / formats.at("xml"));
            const Scene json = load_scene(course_folder / formats.at("json"));
            const std::vector<std::string> differences = compare_scenes(xml, json);
            const auto known = known_twin_differences.find(name);
            const std::vector<std::string> expected =
                known != known_twin_differences.end() ? known->second : std::vector<std::string>();
            std::string listed;
            for (std::size_t i = 0; i < differences.size() && i < 10; ++i) listed += "\n  " + differences[i];
            CHECK_MESSAGE(differences == expected, differences.size() << " differences:" << listed);
            if (!expected.empty()) MESSAGE(name << ": the files differ as known: " << expected.front());
        } catch (const std::exception& error) {
            FAIL_CHECK(error.what());
        }
    }
    CHECK(pairs > 0);
    MESSAGE(pairs << " scenes compared in XML and JSON");
}

TEST_CASE("simple.xml: camera, light, material, a two-triangle mesh, a triangle and a sphere") {
    const fs::path file = course_folder / "hw1/2022F_Batucan2601/System_Files/inputs/simple.xml";
    if (!fs::exists(file)) {
        MESSAGE("skipped: no " << file);
        return;
    }
    const Scene scene = load_scene(file);
    CHECK(scene.source == file);
    CHECK(near(scene.background_color, Vec3(0.0)));
    CHECK(scene.shadow_ray_epsilon == doctest::Approx(1e-3));
    CHECK(scene.intersection_test_epsilon == doctest::Approx(1e-6));
    CHECK(scene.max_recursion_depth == 6);  // absent: the course's default
    CHECK(near(scene.ambient_light, Vec3(25.0)));

    REQUIRE(scene.cameras.size() == 1);
    const auto& camera = scene.cameras[0];
    CHECK(camera.id == "1");
    CHECK(near(camera.position, Vec3(0, 0, 0)));
    CHECK(near(camera.gaze, Vec3(0, 0, -1)));
    CHECK(near(camera.up, Vec3(0, 1, 0)));
    CHECK(camera.near_left == -1.0);
    CHECK(camera.near_right == 1.0);
    CHECK(camera.near_bottom == -1.0);
    CHECK(camera.near_top == 1.0);
    CHECK(camera.near_distance == 1.0);
    CHECK(camera.width == 800);
    CHECK(camera.height == 800);
    CHECK(camera.image_name == "simple.png");
    CHECK_FALSE(camera.left_handed);
    CHECK(camera.num_samples == 1);

    REQUIRE(scene.point_lights.size() == 1);
    CHECK(near(scene.point_lights[0].position, Vec3(0, 0, 0)));  // "0 0 0 " with a trailing blank
    CHECK(near(scene.point_lights[0].intensity, Vec3(1000.0)));

    REQUIRE(scene.materials.size() == 1);
    CHECK(scene.materials[0].type == prism::scene::MaterialType::blinn_phong);
    CHECK(near(scene.materials[0].diffuse, Vec3(1.0)));
    CHECK(scene.materials[0].phong_exponent == 1.0);

    // The Mesh (faces 3 1 2, 1 3 4) and the Triangle (5 6 7), each with its own vertices, in order
    // of first use, shared vertices kept shared.
    REQUIRE(scene.meshes.size() == 2);
    const auto& mesh = scene.meshes[0];
    CHECK(mesh.id == "1");
    CHECK(mesh.shading == prism::scene::ShadingMode::flat);
    REQUIRE(mesh.triangles.size() == 2);
    REQUIRE(mesh.positions.size() == 4);
    CHECK(mesh.triangles[0] == std::array<std::uint32_t, 3>{0, 1, 2});
    CHECK(mesh.triangles[1] == std::array<std::uint32_t, 3>{1, 0, 3});
    CHECK(near(mesh.positions[0], Vec3(0.5, -0.5, -2)));   // vertex 3
    CHECK(near(mesh.positions[1], Vec3(-0.5, 0.5, -2)));   // vertex 1
    CHECK(near(mesh.positions[2], Vec3(-0.5, -0.5, -2)));  // vertex 2
    CHECK(near(mesh.positions[3], Vec3(0.5, 0.5, -2)));    // vertex 4
    CHECK(mesh.normals.empty());
    CHECK(mesh.uvs.empty());
    CHECK(near(mesh.transform, glm::dmat4(1.0)));

    const auto& triangle = scene.meshes[1];
    REQUIRE(triangle.triangles.size() == 1);
    REQUIRE(triangle.positions.size() == 3);
    CHECK(near(triangle.positions[0], Vec3(0.75, 0.75, -2)));
    CHECK(near(triangle.positions[1], Vec3(1, 0.75, -2)));
    CHECK(near(triangle.positions[2], Vec3(0.875, 1, -2)));

    REQUIRE(scene.spheres.size() == 1);
    CHECK(near(scene.spheres[0].center, Vec3(-0.875, 1, -2)));  // vertex 8
    CHECK(scene.spheres[0].radius == 0.3);
    CHECK(scene.planes.empty());
    CHECK(scene.mesh_instances.empty());
    CHECK(scene.unsupported.empty());
}

TEST_CASE("a lookAt camera gets its gaze from GazePoint and its near plane from FovY") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.camera = R"(<Camera id="7" type="lookAt" handedness="left">
            <Position>1 2 10</Position>
            <GazePoint>1 2 0</GazePoint>
            <Up>0 1 0</Up>
            <FovY>60</FovY>
            <NearDistance>2</NearDistance>
            <ImageResolution>300 200</ImageResolution>
            <NumSamples>4</NumSamples>
            <ImageName>look.exr</ImageName>
        </Camera>)";
    const Scene scene = load_scene(folder.write("look_at.xml", scene_xml(parts)));
    REQUIRE(scene.cameras.size() == 1);
    const auto& camera = scene.cameras[0];
    CHECK(near(camera.gaze, Vec3(0, 0, -10)));
    const double top = 2.0 * std::tan(glm::radians(30.0));  // FovY is the full vertical angle
    CHECK(camera.near_top == doctest::Approx(top).epsilon(1e-14));
    CHECK(camera.near_bottom == doctest::Approx(-top).epsilon(1e-14));
    CHECK(camera.near_right == doctest::Approx(top * 1.5).epsilon(1e-14));
    CHECK(camera.near_left == doctest::Approx(-top * 1.5).epsilon(1e-14));
    CHECK(camera.near_distance == 2.0);
    CHECK(camera.left_handed);
    CHECK(camera.num_samples == 4);
    CHECK(camera.image_name == "look.exr");
}

TEST_CASE("transformations apply in the order written (metal_glass_plates.xml, simple_transform.xml)") {
    const fs::path plates = course_folder / "hw2/2022F_Batucan2601/System_Files/hw2/inputs/metal_glass_plates.xml";
    const fs::path simple = course_folder / "hw2/2022F_Batucan2601/System_Files/hw2/inputs/simple_transform.xml";
    if (!fs::exists(plates) || !fs::exists(simple)) {
        MESSAGE("skipped: no " << plates << " or " << simple);
        return;
    }
    const double c = std::cos(glm::radians(20.0)), s = std::sin(glm::radians(20.0));
    {
        // Mesh 2: "s2 s3 r1 t1" = scale 10 10 10, scale 1 1 0.1, 20 degrees about y, translate (1, 5.001, -14).
        const Scene scene = load_scene(plates);
        REQUIRE(scene.meshes.size() == 3);
        glm::dmat4 expected(1.0);  // [column][row]
        expected[0] = {10 * c, 0, -10 * s, 0};
        expected[1] = {0, 10, 0, 0};
        expected[2] = {s, 0, c, 0};
        expected[3] = {1, 5.001, -14, 1};
        CHECK(near(scene.meshes[1].transform, expected));
        // Its vertex 5 (-0.5, -0.5, 0.5): scaled (-5, -5, 0.5), turned, moved.
        const Vec3 moved = prism::transform_point(scene.meshes[1].transform, Vec3(-0.5, -0.5, 0.5));
        CHECK(near(moved, Vec3(-5 * c + 0.5 * s + 1, -5 + 5.001, 5 * s + 0.5 * c - 14)));
        // MeshInstance 4: base mesh 3 ("s2 s3 r2 t2"), then its own t3, since resetTransform="false".
        REQUIRE(scene.mesh_instances.size() == 1);
        CHECK(scene.mesh_instances[0].base_mesh == 2);
        CHECK(scene.mesh_instances[0].material == 2);  // its own material id 3
        CHECK(near(scene.mesh_instances[0].transform, prism::translation({0, 0, -10}) * scene.meshes[2].transform));
    }
    {
        // r1: 20 degrees about z, counter-clockwise.
        const Scene scene = load_scene(simple);
        REQUIRE(scene.meshes.size() == 2);
        glm::dmat4 expected(1.0);
        expected[0] = {c, s, 0, 0};
        expected[1] = {-s, c, 0, 0};
        CHECK(near(scene.meshes[0].transform, expected));
        CHECK(near(scene.meshes[1].transform, expected));
        CHECK(near(scene.spheres[0].transform, glm::dmat4(1.0)));
    }
}

TEST_CASE("mesh instances compose transforms, with and without resetTransform, in XML and JSON") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.transformations = R"(<Translation id="1">1 0 0</Translation>
        <Scaling id="1">2 2 2</Scaling>
        <Rotation id="1">90 0 0 1</Rotation>)";
    // The instances come before the mesh they name, and one names another instance.
    parts.objects = R"(<MeshInstance id="10" baseMeshId="5" resetTransform="false"><Transformations>s1</Transformations></MeshInstance>
        <MeshInstance id="11" baseMeshId="5" resetTransform="true"><Material>2</Material><Transformations>s1</Transformations></MeshInstance>
        <MeshInstance id="12" baseMeshId="10"><Transformations>r1</Transformations></MeshInstance>
        <Mesh id="5"><Material>1</Material><Transformations>t1</Transformations><Faces>1 2 3</Faces></Mesh>)";
    const std::string json = R"({"Scene": {
        "Cameras": {"Camera": {"_id": "1", "Position": "0 0 0", "Gaze": "0 0 -1", "Up": "0 1 0",
                               "NearPlane": "-1 1 -1 1", "NearDistance": "1", "ImageResolution": "16 16",
                               "ImageName": "out.png"}},
        "Lights": {"AmbientLight": "25 25 25",
                   "PointLight": {"_id": "1", "Position": "0 0 0", "Intensity": "1000 1000 1000"}},
        "Materials": {"Material": [
            {"_id": "1", "AmbientReflectance": "1 1 1", "DiffuseReflectance": "1 1 1", "SpecularReflectance": "1 1 1"},
            {"_id": "2", "_type": "mirror", "MirrorReflectance": "1 1 1"}]},
        "Transformations": {"Translation": {"_data": "1 0 0", "_id": "1"}, "Scaling": {"_data": "2 2 2", "_id": "1"},
                            "Rotation": [{"_data": "90 0 0 1", "_id": "1"}]},
        "VertexData": {"_data": "-0.5 0.5 -2 -0.5 -0.5 -2 0.5 -0.5 -2", "_type": "xyz"},
        "TexCoordData": null,
        "Objects": {
            "MeshInstance": [
                {"_id": "10", "_baseMeshId": "5", "_resetTransform": "false", "Transformations": "s1"},
                {"_id": "11", "_baseMeshId": "5", "_resetTransform": "true", "Material": "2", "Transformations": "s1"},
                {"_id": "12", "_baseMeshId": "10", "Transformations": "r1"}],
            "Mesh": {"_id": "5", "Material": "1", "Transformations": "t1", "Faces": {"_data": "1 2 3", "_type": "triangle"}}}
    }})";
    const Scene from_xml = load_scene(folder.write("instances.xml", scene_xml(parts)));
    const Scene from_json = load_scene(folder.write("instances.json", json));
    for (const Scene* scene : {&from_xml, &from_json}) {
        CAPTURE(scene->source);
        REQUIRE(scene->meshes.size() == 1);
        REQUIRE(scene->mesh_instances.size() == 3);
        const glm::dmat4 t1 = prism::translation({1, 0, 0}), s1 = prism::scaling({2, 2, 2});
        const glm::dmat4 r1 = prism::rotation(90.0, {0, 0, 1});
        CHECK(near(scene->meshes[0].transform, t1));
        const auto& composed = scene->mesh_instances[0];
        CHECK(composed.id == "10");
        CHECK(composed.base_mesh == 0);
        CHECK(near(composed.transform, s1 * t1));
        CHECK(composed.material == 0);  // none given: the base mesh's
        const auto& reset = scene->mesh_instances[1];
        CHECK(near(reset.transform, s1));
        CHECK(reset.material == 1);
        const auto& of_instance = scene->mesh_instances[2];  // resolves to mesh 5, after instance 10
        CHECK(of_instance.base_mesh == 0);
        CHECK(near(of_instance.transform, r1 * s1 * t1));
        CHECK(of_instance.material == 0);
        // The mesh's vertex (-0.5, 0.5, -2) through instance 10: moved to (0.5, 0.5, -2), then doubled.
        CHECK(near(prism::transform_point(composed.transform, Vec3(-0.5, 0.5, -2)), Vec3(1, 1, -4)));
    }
    CHECK(compare_scenes(from_xml, from_json).empty());
}

TEST_CASE("unsupported elements are named once each and skipped") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.objects += R"(<LightSphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius><Radiance>1 1 1</Radiance></LightSphere>
        <LightSphere id="2"><Material>1</Material><Center>1</Center><Radius>1</Radius><Radiance>1 1 1</Radiance></LightSphere>
        <Sphere id="1"><Material>1</Material><Center>1</Center><Radius>0.5</Radius></Sphere>)";
    std::string xml = scene_xml(parts);
    xml.replace(xml.find("</Lights>"), 0, "<LightMesh id=\"1\"><Material>1</Material></LightMesh>\n");
    xml.replace(xml.find("</Scene>"), 0, "<Textures></Textures>\n<BRDFs><OriginalPhong id=\"1\"><Exponent>2</Exponent></OriginalPhong></BRDFs>\n");
    const Scene scene = load_scene(folder.write("later_topics.xml", xml));
    // A LightMesh belongs in <Objects>; in <Lights> it is not read. LightSpheres are spheres;
    // <BRDFs> is read (test_brdf.cpp).
    CHECK(scene.unsupported == std::vector<std::string>{"LightMesh"});
    CHECK(scene.spheres.size() == 3);
    CHECK(scene.point_lights.size() == 1);
}

TEST_CASE("the type attribute makes mirrors; an untyped Transparency makes glass") {
    TemporaryFolder folder;
    std::string xml = scene_xml(SceneParts{});
    xml.replace(xml.find("</Materials>"), 0, R"(<Material id="3"><MirrorReflectance>0.5 0.5 0.5</MirrorReflectance></Material>
        <Material id="4"><Transparency>0.9 0.9 0.9</Transparency><RefractionIndex>1.5</RefractionIndex></Material>
        )");
    const Scene scene = load_scene(folder.write("material_types.xml", xml));
    REQUIRE(scene.materials.size() == 4);
    CHECK(scene.materials[1].type == prism::scene::MaterialType::mirror);
    // Untyped with a mirror colour: Blinn-Phong, as the course's images of such scenes show.
    CHECK(scene.materials[2].type == prism::scene::MaterialType::blinn_phong);
    CHECK(near(scene.materials[2].mirror, Vec3(0.5)));
    CHECK(scene.materials[3].type == prism::scene::MaterialType::dielectric);
    CHECK(near(scene.materials[3].transparency, Vec3(0.9)));

    // As 2017-2019 files mean it: the untyped mirror colour makes a mirror; the others keep theirs.
    prism::io::LoadOptions legacy;
    legacy.untyped_mirrors_reflect = true;
    const Scene old = load_scene(folder.path() / "material_types.xml", legacy);
    REQUIRE(old.materials.size() == 4);
    CHECK(old.materials[0].type == prism::scene::MaterialType::blinn_phong);
    CHECK(old.materials[1].type == prism::scene::MaterialType::mirror);
    CHECK(old.materials[2].type == prism::scene::MaterialType::mirror);
    CHECK(old.materials[3].type == prism::scene::MaterialType::dielectric);
}

TEST_CASE("numbers in any course spelling parse; TexCoordData and vertexOffset reach the mesh") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.vertices = "\t-0.5 0.5 -2\t\n 7.7898e-009 -0.5 -2.0E+0 \t\n +0.5 -0.5 -2   \n 9 9 9";
    parts.objects = R"(<Mesh id="1" shadingMode="smooth"><Material>1</Material><Faces vertexOffset="1" textureOffset="1">0 1 2 2 1 0</Faces></Mesh>)";
    std::string xml = scene_xml(parts);
    xml.replace(xml.find("<Objects>"), 0, "<TexCoordData>0 0  1 0  1 1  0 1</TexCoordData>\n");
    const Scene scene = load_scene(folder.write("numbers.xml", xml));
    REQUIRE(scene.meshes.size() == 1);
    const auto& mesh = scene.meshes[0];
    CHECK(mesh.shading == prism::scene::ShadingMode::smooth);
    REQUIRE(mesh.positions.size() == 3);  // both faces use the same three vertices
    CHECK(mesh.positions[1].x == 7.7898e-9);
    CHECK(mesh.positions[2].x == 0.5);
    CHECK(mesh.triangles[1] == std::array<std::uint32_t, 3>{2, 1, 0});
    REQUIRE(mesh.uvs.size() == 3);
    CHECK(mesh.uvs[0] == prism::scene::Vec2(0, 0));
    CHECK(mesh.uvs[2] == prism::scene::Vec2(1, 1));
}

// ---- broken input: each names the file and the element --------------------------------------

namespace {

// A binary data file as the course writes it: an int32 record count, then the values.
template <class Value>
std::string binary_records(std::int32_t count, const std::vector<Value>& values) {
    std::string bytes(sizeof count + values.size() * sizeof(Value), '\0');
    std::memcpy(bytes.data(), &count, sizeof count);
    if (!values.empty()) std::memcpy(bytes.data() + sizeof count, values.data(), values.size() * sizeof(Value));
    return bytes;
}

}  // namespace

TEST_CASE("binaryFile vertex data, texture coordinates and faces read like their text forms") {
    TemporaryFolder folder;
    folder.write("vertices.bin", binary_records<float>(4, {0, 0, -2, 1, 0, -2, 1, 1, -2, 0, 1, -2}));
    folder.write("uv.bin", binary_records<float>(4, {0, 0, 1, 0, 1, 1, 0, 1}));
    folder.write("faces.bin", binary_records<std::int32_t>(2, {1, 2, 3, 1, 3, 4}));
    SceneParts parts;
    parts.vertices = "";
    parts.objects = R"(<Mesh id="1"><Material>1</Material><Faces binaryFile="faces.bin"/></Mesh>)";
    std::string xml = scene_xml(parts);
    xml.replace(xml.find("<VertexData>"), std::string("<VertexData>").size(), R"(<VertexData binaryFile="vertices.bin">)");
    xml.replace(xml.find("</Scene>"), 0, R"(<TexCoordData binaryFile="uv.bin"/>)" "\n");
    const fs::path scene_file = folder.write("binary.xml", xml);
    const Scene scene = load_scene(scene_file);
    REQUIRE(scene.meshes.size() == 1);
    const auto& mesh = scene.meshes[0];
    REQUIRE(mesh.triangles.size() == 2);
    REQUIRE(mesh.positions.size() == 4);
    CHECK(near(mesh.positions[mesh.triangles[1][2]], Vec3(0, 1, -2)));
    REQUIRE(mesh.uvs.size() == 4);
    CHECK(mesh.uvs[mesh.triangles[0][1]] == glm::dvec2(1, 0));

    // A count the file cannot hold is one clear error naming the file and the element.
    folder.write("faces.bin", binary_records<std::int32_t>(1000000, {1, 2, 3}));
    const std::string message = load_error_of([&] { load_scene(scene_file); });
    CHECK(contains(message, "faces.bin"));
    CHECK(contains(message, "Faces"));
    CHECK(contains(message, "declares 1000000 records"));
}

TEST_CASE("malformed XML: an unclosed tag") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.objects = "<Mesh id=\"1\"><Material>1</Material><Faces>1 2 3</Faces></Mesh";
    const std::string xml = scene_xml(parts);
    const std::string message = check_load_error(folder.write("unclosed.xml", xml), "<Mesh id=\"1\">");
    CHECK(contains(message, "malformed XML"));
    // pugixml stops at the next tag, </Objects>, on the line after the unclosed </Mesh.
    const auto line = 1 + std::count(xml.begin(), xml.begin() + std::ptrdiff_t(xml.find("</Objects>")), '\n');
    CHECK_MESSAGE(contains(message, "(line " + std::to_string(line) + ","), message);
}

TEST_CASE("malformed JSON: a missing comma") {
    TemporaryFolder folder;
    const std::string json = R"({"Scene": {
  "Objects": { "Sphere": { "_id": "1", "Material": "1", "Center": "1" "Radius": "0.3" } }
}})";
    const std::string message = check_load_error(folder.write("missing_comma.json", json), "<Sphere id=\"1\">");
    CHECK(contains(message, "malformed JSON"));
    CHECK(contains(message, "line 2"));
}

TEST_CASE("missing PLY file") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.objects = R"(<Mesh id="1"><Material>1</Material><Faces plyFile="does_not_exist.ply"/></Mesh>)";
    const std::string message = check_load_error(folder.write("missing_ply.xml", scene_xml(parts)), "<Faces>");
    CHECK(contains(message, "does_not_exist.ply"));
}

TEST_CASE("PLY file truncated in the middle of its vertices") {
    TemporaryFolder folder;
    std::string ply =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
    const float coordinates[] = {-0.5f, 0.5f, -2.0f, -0.5f, -0.5f, -2.0f, 0.5f, -0.5f};  // 2.67 of 4 vertices
    ply.append(reinterpret_cast<const char*>(coordinates), sizeof coordinates);
    folder.write("truncated.ply", ply);
    SceneParts parts;
    parts.objects = R"(<Mesh id="1"><Material>1</Material><Faces plyFile="truncated.ply"/></Mesh>)";
    const std::string message = check_load_error(folder.write("truncated_ply.xml", scene_xml(parts)), "<Faces>");
    CHECK(contains(message, "truncated.ply"));
}

TEST_CASE("unknown material id") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.objects = R"(<Mesh id="3"><Material>7</Material><Faces>1 2 3</Faces></Mesh>)";
    const std::string message =
        check_load_error(folder.write("unknown_material.xml", scene_xml(parts)), "<Mesh id=\"3\">/<Material>");
    CHECK(contains(message, "unknown material id \"7\""));
}

TEST_CASE("negative image size") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.camera.replace(parts.camera.find("16 16"), 5, "-16 16");
    check_load_error(folder.write("negative_size.xml", scene_xml(parts)), "<Camera id=\"1\">/<ImageResolution>");
}

TEST_CASE("non-numeric value") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.objects = R"(<Sphere id="1"><Material>1</Material><Center>1</Center><Radius>abc</Radius></Sphere>)";
    const std::string message = check_load_error(folder.write("not_a_number.xml", scene_xml(parts)), "<Radius>");
    CHECK(contains(message, "\"abc\" is not a number"));
}

TEST_CASE("NaN and infinite values") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.vertices = "-0.5 0.5 -2 -0.5 nan -2 0.5 -0.5 -2";
    check_load_error(folder.write("nan.xml", scene_xml(parts)), "<VertexData>");
    parts.vertices = "-0.5 0.5 -2 -0.5 -0.5 -2 0.5 -0.5 inf";
    check_load_error(folder.write("inf.xml", scene_xml(parts)), "<VertexData>");
}

TEST_CASE("vertex index out of range") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.objects = R"(<Mesh id="1"><Material>1</Material><Faces>1 2 9</Faces></Mesh>)";
    const std::string message = check_load_error(folder.write("vertex_out_of_range.xml", scene_xml(parts)), "<Faces>");
    CHECK(contains(message, "vertex index 9"));
    parts.objects = R"(<Sphere id="1"><Material>1</Material><Center>4</Center><Radius>1</Radius></Sphere>)";
    check_load_error(folder.write("center_out_of_range.xml", scene_xml(parts)), "<Center>");
    parts.objects = R"(<Mesh id="1"><Material>1</Material><Faces>0 1 2</Faces></Mesh>)";  // indices start at 1
    check_load_error(folder.write("zero_index.xml", scene_xml(parts)), "<Faces>");
}

TEST_CASE("missing required element and wrong number of components") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.objects = R"(<Sphere id="2"><Material>1</Material><Center>1</Center></Sphere>)";
    const std::string message = check_load_error(folder.write("no_radius.xml", scene_xml(parts)), "<Sphere id=\"2\">");
    CHECK(contains(message, "missing <Radius>"));
    parts = SceneParts();
    parts.camera.replace(parts.camera.find("<Position>0 0 0</Position>"), 26, "");
    check_load_error(folder.write("no_position.xml", scene_xml(parts)), "<Camera id=\"1\">");
    parts = SceneParts();
    parts.camera.replace(parts.camera.find("0 1 0"), 5, "0 1");
    check_load_error(folder.write("short_up.xml", scene_xml(parts)), "<Up>");
}

TEST_CASE("unknown transformation kind or id, unknown base mesh") {
    TemporaryFolder folder;
    SceneParts parts;
    parts.transformations = "<Translation id=\"1\">0 0 1</Translation>";
    parts.objects = R"(<Mesh id="1"><Material>1</Material><Transformations>t1 x3</Transformations><Faces>1 2 3</Faces></Mesh>)";
    std::string message = check_load_error(folder.write("kind.xml", scene_xml(parts)), "<Mesh id=\"1\">/<Transformations>");
    CHECK(contains(message, "x3"));
    parts.objects = R"(<Mesh id="1"><Material>1</Material><Transformations>t1 t2</Transformations><Faces>1 2 3</Faces></Mesh>)";
    message = check_load_error(folder.write("id.xml", scene_xml(parts)), "<Transformations>");
    CHECK(contains(message, "t2"));
    parts.objects = R"(<Mesh id="1"><Material>1</Material><Faces>1 2 3</Faces></Mesh>
        <MeshInstance id="2" baseMeshId="9"/>)";
    check_load_error(folder.write("base.xml", scene_xml(parts)), "<MeshInstance id=\"2\">");
}

TEST_CASE("a file that is neither .xml nor .json") {
    TemporaryFolder folder;
    CHECK_THROWS_AS(load_scene(folder.write("scene.txt", "<Scene/>")), LoadError);
    CHECK_THROWS_AS(load_scene(fs::path("no_such_scene.xml")), LoadError);
}
