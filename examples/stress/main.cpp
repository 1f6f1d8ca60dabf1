// prism-stress: writes the scenes that stress a ray tracer's precision: a course mesh subdivided
// into tiny triangles, scaled and moved away from the origin (the tiny-triangle dragon is
// dragon_lowres subdivided three times), and a closed, randomly perturbed icosphere for leak
// tests. Each scene is a CENG795 XML file plus a binary PLY (double coordinates, so a mesh moved
// 10^4 away keeps its shape) that `prism` renders as it is.
#include <prism/geometry/subdivide.hpp>
#include <prism/io/load.hpp>
#include <prism/io/ply.hpp>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

namespace fs = std::filesystem;

namespace {

constexpr const char* usage = R"(usage: prism-stress mesh INPUT [options] --output SCENE.xml
       prism-stress sphere [options] --output SCENE.xml

Writes a stress scene for precision tests: SCENE.xml (CENG795 format: one camera framing the
mesh, one point light, one diffuse material) and SCENE.ply next to it (binary, double
coordinates). `prism SCENE.xml` renders it.

mesh INPUT       a PLY file, or a scene file (.xml, .json) whose mesh is taken with its
                 transformation applied. Every triangle is split into four at its edge
                 midpoints N times (4^N times the triangles, the same surface; midpoints are
                 shared, so a closed mesh stays closed), then the mesh is scaled about its
                 centroid (area-weighted) and moved by the offset.
  --mesh ID        the mesh of a scene file to take (default: the one with most triangles)
  --subdivide N    levels of midpoint subdivision (default 0)
  --perturb A      move each new midpoint along the surface normal by up to A times its
                   edge's length, uniformly at random (default 0: vertices stay on the
                   original triangles); A in [0, 0.5)

sphere           a closed icosphere of radius 1 (before --scale) centred on the origin (before
                 --offset), 20 * 4^N triangles with shared vertices, each vertex moved
                 radially by a factor in [1 - A, 1 + A]
  --subdivisions N icosahedron subdivisions (default 5: 20,480 triangles)
  --perturb A      radial amplitude, in [0, 1) (default 0.05)

common options:
  --seed K             seed of the random perturbation (default 1)
  --scale S            scale factor, > 0 (default 1)
  --offset X Y Z       translation applied after scaling (default 0 0 0)
  --resolution W H     the camera's image size (default 800 800)
  --output SCENE.xml   the scene file to write (required); the PLY gets its name with .ply
  --help               this text

The tiny-triangle dragon (>= 750,000 triangles at its original size):
  prism-stress mesh ../shared/ceng795/hw1/2020_ozgurcanc/assets/scenes/dragon_lowres.xml \
      --subdivide 3 --output dragon_tiny.xml
The same dragon moved 10^4 from the origin:
  prism-stress mesh .../dragon_lowres.xml --subdivide 3 --offset 10000 10000 10000 --output dragon_far.xml
A leak-test sphere of radius 10^-3 at 10^4:
  prism-stress sphere --subdivisions 6 --perturb 0.01 --seed 7 --scale 1e-3 --offset 1e4 0 0 --output leak.xml

exit status: 0 on success, 1 when the input cannot be read or the output not written, 2 for
usage errors.
)";

// Subdivision stops before it would exceed this many triangles (about 5 GB while it runs).
constexpr std::uint64_t max_triangles = 100'000'000;

[[noreturn]] void usage_error(const std::string& message) {
    std::cerr << "prism-stress: " << message << "\n(see prism-stress --help)\n";
    std::exit(2);
}

template <class Number>
Number parse_number(std::string_view option, std::string_view text) {
    Number value{};
    if (!text.empty() && text[0] == '+') text.remove_prefix(1);
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size())
        usage_error(std::string(option) + ": not a number: '" + std::string(text) + "'");
    if constexpr (std::is_floating_point_v<Number>) {
        if (!std::isfinite(value)) usage_error(std::string(option) + ": not a finite number: '" + std::string(text) + "'");
    }
    return value;
}

enum class Command { mesh, sphere };

struct Arguments {
    Command command = Command::mesh;
    fs::path input;
    std::optional<std::string> mesh_id;
    int levels = -1;  // --subdivide / --subdivisions; -1: the command's default
    std::optional<double> perturb;
    std::uint64_t seed = 1;
    double scale = 1.0;
    glm::dvec3 offset{0.0};
    int width = 800, height = 800;
    fs::path output;
};

Arguments parse_arguments(int argc, char** argv) {
    std::vector<std::string_view> args(argv + 1, argv + argc);
    for (const auto arg : args)
        if (arg == "--help" || arg == "-h") {
            std::cout << usage;
            std::exit(0);
        }
    if (args.empty()) usage_error("no command given (mesh or sphere)");
    Arguments arguments;
    if (args[0] == "mesh") arguments.command = Command::mesh;
    else if (args[0] == "sphere") arguments.command = Command::sphere;
    else usage_error("unknown command '" + std::string(args[0]) + "' (expected mesh or sphere)");
    const bool is_mesh = arguments.command == Command::mesh;
    for (std::size_t i = 1; i < args.size(); ++i) {
        const std::string_view arg = args[i];
        const auto value = [&]() -> std::string_view {
            if (i + 1 >= args.size()) usage_error(std::string(arg) + " needs a value");
            return args[++i];
        };
        if (arg == "--mesh" && is_mesh) {
            arguments.mesh_id = std::string(value());
        } else if ((arg == "--subdivide" && is_mesh) || (arg == "--subdivisions" && !is_mesh)) {
            arguments.levels = parse_number<int>(arg, value());
            if (arguments.levels < 0) usage_error(std::string(arg) + " must not be negative");
        } else if (arg == "--perturb") {
            arguments.perturb = parse_number<double>(arg, value());
            const double limit = is_mesh ? 0.5 : 1.0;
            if (!(*arguments.perturb >= 0 && *arguments.perturb < limit))
                usage_error("--perturb must be in [0, " + std::string(is_mesh ? "0.5" : "1") + ")");
        } else if (arg == "--seed") {
            arguments.seed = parse_number<std::uint64_t>(arg, value());
        } else if (arg == "--scale") {
            arguments.scale = parse_number<double>(arg, value());
            if (!(arguments.scale > 0)) usage_error("--scale must be positive");
        } else if (arg == "--offset") {
            for (int axis = 0; axis < 3; ++axis) arguments.offset[axis] = parse_number<double>(arg, value());
        } else if (arg == "--resolution") {
            arguments.width = parse_number<int>(arg, value());
            arguments.height = parse_number<int>(arg, value());
            if (arguments.width < 1 || arguments.height < 1) usage_error("--resolution needs two positive sizes");
        } else if (arg == "--output") {
            arguments.output = fs::path(value());
        } else if (!arg.empty() && arg[0] == '-') {
            usage_error("unknown option " + std::string(arg) + " for the " + std::string(args[0]) + " command");
        } else if (is_mesh && arguments.input.empty()) {
            arguments.input = fs::path(arg);
        } else {
            usage_error("unexpected argument '" + std::string(arg) + "'");
        }
    }
    if (is_mesh && arguments.input.empty()) usage_error("mesh: no INPUT given (a PLY or scene file)");
    if (arguments.output.empty()) usage_error("no --output SCENE.xml given");
    if (arguments.output.extension() != ".xml") usage_error("--output must name an .xml scene file");
    if (arguments.output.stem().empty()) usage_error("--output needs a file name");
    return arguments;
}

std::string lowercase_extension(const fs::path& path) {
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return extension;
}

prism::IndexedMesh<double> read_input_mesh(const Arguments& arguments) {
    if (lowercase_extension(arguments.input) == ".ply") {
        if (arguments.mesh_id) throw std::runtime_error("--mesh applies to scene files, not to a PLY file");
        prism::io::PlyMesh ply = prism::io::read_ply(arguments.input);
        prism::IndexedMesh<double> mesh;
        mesh.positions = std::move(ply.positions);
        mesh.triangles = std::move(ply.triangles);
        return mesh;
    }
    const prism::scene::Scene scene = prism::io::load_scene(arguments.input);
    if (scene.meshes.empty()) throw std::runtime_error(arguments.input.string() + ": the scene has no mesh");
    const prism::scene::Mesh* chosen = nullptr;
    if (arguments.mesh_id) {
        for (const auto& mesh : scene.meshes)
            if (mesh.id == *arguments.mesh_id) {
                chosen = &mesh;
                break;
            }
        if (chosen == nullptr) {
            std::string ids;
            for (const auto& mesh : scene.meshes) ids += (ids.empty() ? "" : ", ") + mesh.id;
            throw std::runtime_error(arguments.input.string() + ": no mesh with id \"" + *arguments.mesh_id +
                                     "\" (the meshes are: " + ids + ")");
        }
    } else {
        chosen = &*std::max_element(scene.meshes.begin(), scene.meshes.end(), [](const auto& a, const auto& b) {
            return a.triangles.size() < b.triangles.size();
        });
    }
    return prism::world_space_mesh(*chosen);
}

// The surface's centroid: triangle centroids weighted by area, so it does not move when the
// mesh is subdivided more densely in one place than another.
glm::dvec3 area_centroid(const prism::IndexedMesh<double>& mesh) {
    glm::dvec3 sum(0.0);
    double total_area = 0.0;
    for (const auto& [a, b, c] : mesh.triangles) {
        const glm::dvec3 &p0 = mesh.positions[a], &p1 = mesh.positions[b], &p2 = mesh.positions[c];
        const double area = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
        sum += area * (p0 + p1 + p2) / 3.0;
        total_area += area;
    }
    if (total_area > 0) return sum / total_area;
    glm::dvec3 mean(0.0);
    for (const auto& p : mesh.positions) mean += p;
    return mesh.positions.empty() ? mean : mean / double(mesh.positions.size());
}

// Writes through a temporary file renamed into place, so a failed run leaves no partial file.
template <class Write>
void write_atomically(const fs::path& path, Write&& write) {
    const fs::path temporary = path.string() + ".tmp-" + std::to_string(::getpid());
    try {
        std::ofstream stream(temporary, std::ios::binary | std::ios::trunc);
        if (!stream) throw std::runtime_error(path.string() + ": cannot open for writing");
        write(stream);
        stream.flush();
        if (!stream) throw std::runtime_error(path.string() + ": write error");
        stream.close();
        fs::rename(temporary, path);
    } catch (...) {
        std::error_code ignored;
        fs::remove(temporary, ignored);
        throw;
    }
}

template <class T>
void write_little_endian(std::ostream& stream, T value) {
    static_assert(std::endian::native == std::endian::little, "the PLY writer assumes a little-endian machine");
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    stream.write(bytes, sizeof(T));
}

void write_ply(const fs::path& path, const prism::IndexedMesh<double>& mesh) {
    write_atomically(path, [&](std::ostream& stream) {
        stream << "ply\nformat binary_little_endian 1.0\ncomment written by prism-stress\n"
               << "element vertex " << mesh.positions.size() << "\nproperty double x\nproperty double y\n"
               << "property double z\nelement face " << mesh.triangles.size()
               << "\nproperty list uchar uint vertex_indices\nend_header\n";
        for (const auto& p : mesh.positions)
            for (int axis = 0; axis < 3; ++axis) write_little_endian(stream, p[axis]);
        for (const auto& triangle : mesh.triangles) {
            write_little_endian(stream, std::uint8_t(3));
            for (std::uint32_t index : triangle) write_little_endian(stream, index);
        }
    });
}

std::string vec3_text(const glm::dvec3& v) {
    std::ostringstream text;
    text << std::setprecision(17) << v.x + 0.0 << ' ' << v.y + 0.0 << ' ' << v.z + 0.0;  // + 0.0: no "-0"
    return text.str();
}

std::string number_text(double value) {
    std::ostringstream text;
    text << std::setprecision(17) << value;
    return text.str();
}

struct Bounds {
    glm::dvec3 min{std::numeric_limits<double>::infinity()};
    glm::dvec3 max{-std::numeric_limits<double>::infinity()};
};

Bounds bounds_of(const prism::IndexedMesh<double>& mesh) {
    Bounds bounds;
    for (const auto& p : mesh.positions) {
        bounds.min = glm::min(bounds.min, p);
        bounds.max = glm::max(bounds.max, p);
    }
    return bounds;
}

// A camera looking at the mesh's bounding sphere from the front and a little above, far enough
// for the sphere to fill the narrower side of a 40-degree field of view; a point light above
// and to the left of it, bright enough to light the surface like the course's dragon scene.
void write_scene(const fs::path& path, const std::string& ply_name, const prism::IndexedMesh<double>& mesh,
                 const Arguments& arguments, const std::string& command_line) {
    const Bounds bounds = bounds_of(mesh);
    const glm::dvec3 center = (bounds.min + bounds.max) * 0.5;
    const double radius = std::max(0.5 * glm::length(bounds.max - bounds.min), 1e-300);
    const double half_angle = 20.0 * 3.14159265358979323846 / 180.0;
    const double distance = 1.05 * radius / std::sin(half_angle);
    const glm::dvec3 view = glm::normalize(glm::dvec3(0.0, 0.25, 1.0));
    const glm::dvec3 camera = center + distance * view;
    const glm::dvec3 light = center + distance * glm::normalize(glm::dvec3(-0.6, 0.8, 0.9));
    const double light_distance = glm::length(light - center);
    // The near plane at distance 1, square pixels, its narrower half-side tan(20 degrees).
    const double aspect = double(arguments.width) / arguments.height;
    const double half_height = aspect >= 1 ? std::tan(half_angle) : std::tan(half_angle) / aspect;
    const double half_width = half_height * aspect;
    const double intensity = 250.0 * light_distance * light_distance;
    const std::string image_name = path.stem().string() + ".png";

    write_atomically(path, [&](std::ostream& stream) {
        stream << "<!-- A stress scene written by prism-stress:\n     " << command_line << "\n"
               << "     " << mesh.triangles.size() << " triangles, " << mesh.positions.size() << " vertices in "
               << ply_name << ".\n"
               << "     ShadowRayEpsilon matters only in the course-compatible mode; it is 1e-4 of the bounding radius. -->\n"
               << "<Scene>\n"
               << "    <BackgroundColor>0 0 0</BackgroundColor>\n"
               << "    <ShadowRayEpsilon>" << number_text(1e-4 * radius) << "</ShadowRayEpsilon>\n"
               << "    <Cameras>\n"
               << "        <Camera id=\"1\">\n"
               << "            <Position>" << vec3_text(camera) << "</Position>\n"
               << "            <Gaze>" << vec3_text(-view) << "</Gaze>\n"
               << "            <Up>0 1 0</Up>\n"
               << "            <NearPlane>" << number_text(-half_width) << ' ' << number_text(half_width) << ' '
               << number_text(-half_height) << ' ' << number_text(half_height) << "</NearPlane>\n"
               << "            <NearDistance>1</NearDistance>\n"
               << "            <ImageResolution>" << arguments.width << ' ' << arguments.height << "</ImageResolution>\n"
               << "            <ImageName>" << image_name << "</ImageName>\n"
               << "        </Camera>\n"
               << "    </Cameras>\n"
               << "    <Lights>\n"
               << "        <AmbientLight>25 25 25</AmbientLight>\n"
               << "        <PointLight id=\"1\">\n"
               << "            <Position>" << vec3_text(light) << "</Position>\n"
               << "            <Intensity>" << vec3_text(glm::dvec3(intensity)) << "</Intensity>\n"
               << "        </PointLight>\n"
               << "    </Lights>\n"
               << "    <Materials>\n"
               << "        <Material id=\"1\">\n"
               << "            <AmbientReflectance>0.1 0.1 0.1</AmbientReflectance>\n"
               << "            <DiffuseReflectance>0.65 0.4 0.4</DiffuseReflectance>\n"
               << "            <SpecularReflectance>0 0 0</SpecularReflectance>\n"
               << "            <PhongExponent>1</PhongExponent>\n"
               << "        </Material>\n"
               << "    </Materials>\n"
               << "    <Objects>\n"
               << "        <Mesh id=\"1\">\n"
               << "            <Material>1</Material>\n"
               << "            <Faces plyFile=\"" << ply_name << "\" />\n"
               << "        </Mesh>\n"
               << "    </Objects>\n"
               << "</Scene>\n";
    });
}

// What makes the scene hard: triangle size against the magnitude of the coordinates.
void print_summary(std::ostream& out, const fs::path& scene, const fs::path& ply, const prism::IndexedMesh<double>& mesh) {
    const Bounds bounds = bounds_of(mesh);
    double largest_coordinate = 0.0;
    for (int axis = 0; axis < 3; ++axis)
        largest_coordinate = std::max({largest_coordinate, std::abs(bounds.min[axis]), std::abs(bounds.max[axis])});
    std::vector<double> edges;
    edges.reserve(mesh.triangles.size());
    for (const auto& [a, b, c] : mesh.triangles) {
        (void)c;
        edges.push_back(glm::length(mesh.positions[b] - mesh.positions[a]));
    }
    double median_edge = 0.0;
    if (!edges.empty()) {
        std::nth_element(edges.begin(), edges.begin() + std::ptrdiff_t(edges.size() / 2), edges.end());
        median_edge = edges[edges.size() / 2];
    }
    out << "wrote " << scene.string() << " and " << ply.string() << ": " << mesh.triangles.size() << " triangles, "
        << mesh.positions.size() << " vertices, " << (prism::is_closed(mesh.triangles) ? "closed" : "not closed")
        << "\n  bounds " << vec3_text(bounds.min) << " .. " << vec3_text(bounds.max) << "\n  median edge "
        << median_edge << ", largest coordinate " << largest_coordinate << " (ratio "
        << (largest_coordinate > 0 ? median_edge / largest_coordinate : 0.0) << "; float resolves "
        << std::numeric_limits<float>::epsilon() << ")\n";
}

}  // namespace

int main(int argc, char** argv) {
    const Arguments arguments = parse_arguments(argc, argv);
    std::string command_line = "prism-stress";
    for (int i = 1; i < argc; ++i) command_line += std::string(" ") + argv[i];
    try {
        prism::IndexedMesh<double> mesh;
        const auto check_size = [](std::uint64_t triangles, int levels) {
            std::uint64_t result = triangles;
            for (int level = 0; level < levels; ++level) {
                result *= 4;
                if (result > max_triangles)
                    throw std::runtime_error(std::to_string(levels) + " subdivisions of " + std::to_string(triangles) +
                                             " triangles exceed the limit of " + std::to_string(max_triangles) +
                                             " triangles");
            }
        };
        if (arguments.command == Command::mesh) {
            mesh = read_input_mesh(arguments);
            if (mesh.triangles.empty()) throw std::runtime_error(arguments.input.string() + ": the mesh has no triangles");
            const int levels = std::max(arguments.levels, 0);
            check_size(mesh.triangles.size(), levels);
            prism::SubdivisionOptions options;
            options.perturb = arguments.perturb.value_or(0.0);
            options.seed = arguments.seed;
            mesh = prism::subdivide_midpoint(std::move(mesh), levels, options);
        } else {
            const int levels = arguments.levels < 0 ? 5 : arguments.levels;
            check_size(20, levels);
            mesh = prism::icosphere<double>(levels);
            prism::perturb_radially(mesh, glm::dvec3(0.0), arguments.perturb.value_or(0.05), arguments.seed);
        }
        // A mesh scales about its centroid; the sphere about its centre, which then lies
        // exactly at the offset (leak tests aim rays from there).
        const glm::dvec3 center = arguments.command == Command::mesh ? area_centroid(mesh) : glm::dvec3(0.0);
        for (auto& p : mesh.positions) p = center + (p - center) * arguments.scale + arguments.offset;

        fs::path ply = arguments.output;
        ply.replace_extension(".ply");
        if (!arguments.output.parent_path().empty()) fs::create_directories(arguments.output.parent_path());
        write_ply(ply, mesh);
        write_scene(arguments.output, ply.filename().string(), mesh, arguments, command_line);
        print_summary(std::cout, arguments.output, ply, mesh);
    } catch (const std::exception& error) {
        std::cerr << "prism-stress: " << error.what() << '\n';
        return 1;
    }
    return 0;
}
