// The PLY reader: every format, scalar type and list type written by the test itself, the
// malformed files a user can hand it, and the course's real meshes when the shared data is there.
#include "text_contains.hpp"

#include <prism/io/ply.hpp>

#include <doctest/doctest.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <random>
#include <string>
#include <string_view>
#include <vector>

using prism_test::contains;

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace fs = std::filesystem;
using prism::io::LoadError;
using prism::io::PlyMesh;
using prism::io::read_ply;
using Triangle = std::array<std::uint32_t, 3>;

namespace doctest {
template <glm::length_t N>
struct StringMaker<glm::vec<N, double>> {
    static String convert(const glm::vec<N, double>& vector) {
        std::string text = "(";
        for (glm::length_t i = 0; i < N; ++i) text += (i ? " " : "") + std::to_string(vector[i]);
        return (text + ")").c_str();
    }
};
template <>
struct StringMaker<Triangle> {
    static String convert(const Triangle& t) {
        return ("[" + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "]").c_str();
    }
};
template <class T>
struct StringMaker<std::vector<T>> {
    static String convert(const std::vector<T>& values) {
        String text = "{";
        for (const T& value : values) text += StringMaker<T>::convert(value) + " ";
        return text + "}";
    }
};
}  // namespace doctest

namespace {

// One directory per test process: doctest cases may run as parallel processes under ctest.
class TemporaryDirectory {
public:
    TemporaryDirectory() {
        std::random_device random;
        for (;;) {
            path_ = fs::temp_directory_path() / ("prism_test_ply_" + std::to_string(random()));
            if (fs::create_directory(path_)) break;
        }
    }
    ~TemporaryDirectory() {
        std::error_code ignored;
        fs::remove_all(path_, ignored);
    }
    const fs::path& path() const { return path_; }

private:
    fs::path path_;
};

const fs::path& temporary_directory() {
    static const TemporaryDirectory directory;
    return directory.path();
}

enum class Format { ascii, binary_little_endian, binary_big_endian };
constexpr std::array all_formats{Format::ascii, Format::binary_little_endian, Format::binary_big_endian};

std::string format_name(Format format) {
    switch (format) {
        case Format::ascii: return "ascii";
        case Format::binary_little_endian: return "binary_little_endian";
        case Format::binary_big_endian: return "binary_big_endian";
    }
    return "";
}

const std::vector<std::string> integer_type_names{"char",   "int8",  "uchar", "uint8", "short", "int16",
                                                  "ushort", "uint16", "int",  "int32", "uint",  "uint32"};
const std::vector<std::string> real_type_names{"float", "float32", "double", "float64"};

bool is_signed_type(std::string_view type) {
    return type == "char" || type == "int8" || type == "short" || type == "int16" || type == "int" ||
           type == "int32" || type == "float" || type == "float32" || type == "double" || type == "float64";
}

// The data part of a PLY file, written value by value with the type the header declares, so one
// description of a mesh serves the three formats.
class Body {
public:
    explicit Body(Format format) : format_(format) {}

    Body& value(std::string_view type, double value) {
        if (format_ == Format::ascii) {
            char text[64];
            const auto result = std::to_chars(text, text + sizeof text, value);
            if (!bytes_.empty() && bytes_.back() != '\n') bytes_ += ' ';
            bytes_.append(text, result.ptr);
            return *this;
        }
        if (type == "char" || type == "int8") return put(static_cast<std::int8_t>(value));
        if (type == "uchar" || type == "uint8") return put(static_cast<std::uint8_t>(value));
        if (type == "short" || type == "int16") return put(static_cast<std::int16_t>(value));
        if (type == "ushort" || type == "uint16") return put(static_cast<std::uint16_t>(value));
        if (type == "int" || type == "int32") return put(static_cast<std::int32_t>(value));
        if (type == "uint" || type == "uint32") return put(static_cast<std::uint32_t>(value));
        if (type == "float" || type == "float32") return put(static_cast<float>(value));
        if (type == "double" || type == "float64") return put(value);
        FAIL("test bug: unknown type " << type);
        return *this;
    }

    Body& list(std::string_view count_type, std::string_view item_type, std::initializer_list<double> items) {
        value(count_type, static_cast<double>(items.size()));
        for (double item : items) value(item_type, item);
        return *this;
    }

    // Raw text or bytes, for the malformed cases.
    Body& raw(std::string_view text) {
        bytes_ += text;
        return *this;
    }

    Body& end_record() {
        if (format_ == Format::ascii) bytes_ += '\n';
        return *this;
    }

    const std::string& bytes() const { return bytes_; }

private:
    template <class T>
    Body& put(T value) {
        char bytes[sizeof(T)];
        std::memcpy(bytes, &value, sizeof(T));
        if ((format_ == Format::binary_big_endian) != (std::endian::native == std::endian::big))
            std::reverse(bytes, bytes + sizeof(T));
        bytes_.append(bytes, sizeof(T));
        return *this;
    }

    Format format_;
    std::string bytes_;
};

fs::path write_file(const std::string& name, std::string_view contents) {
    const fs::path path = temporary_directory() / name;
    std::ofstream stream(path, std::ios::binary);
    stream.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    REQUIRE(stream.good());
    return path;
}

std::string header(Format format, std::string_view elements) {
    return "ply\nformat " + format_name(format) + " 1.0\n" + std::string(elements) + "end_header\n";
}

fs::path write_ply(const std::string& name, Format format, std::string_view elements, const Body& body) {
    return write_file(name, header(format, elements) + body.bytes());
}

// Every rejection must name the file, the place, and say what is wrong.
void check_rejects(const fs::path& path, std::string_view element, std::string_view message) {
    CAPTURE(path);
    CHECK_THROWS_AS(read_ply(path), LoadError);
    try {
        read_ply(path);
    } catch (const LoadError& error) {
        CAPTURE(error.what());
        CHECK(contains(error.what(), path.filename().string()));
        CHECK(contains(error.element(), element));
        CHECK(contains(error.what(), message));
    }
}

// The mesh most cases write: a quad and a triangle, with normals and texture coordinates whose
// values are exact in float, so every format must give them back bit for bit.
const std::vector<glm::dvec3> quad_positions{{-1.5, 0.25, 2.0}, {3.0, -0.5, 1024.75}, {0.125, 7.0, -8.5}, {0.0, 1.0, -0.0625}};
const std::vector<glm::dvec3> quad_normals{{0.0, 0.0, 1.0}, {0.0, 1.0, 0.0}, {-1.0, 0.0, 0.0}, {0.5, -0.5, 0.25}};
const std::vector<glm::dvec2> quad_uvs{{0.0, 0.0}, {1.0, 0.0}, {1.0, 0.75}, {0.25, 1.0}};
const std::vector<Triangle> quad_triangles{{0, 1, 2}, {0, 2, 3}, {3, 2, 1}};

Body quad_body(Format format, std::string_view type, std::string_view count_type = "uchar",
               std::string_view index_type = "int") {
    Body body(format);
    for (std::size_t i = 0; i < quad_positions.size(); ++i) {
        for (int axis = 0; axis < 3; ++axis) body.value(type, quad_positions[i][axis]);
        for (int axis = 0; axis < 3; ++axis) body.value(type, quad_normals[i][axis]);
        body.value(type, quad_uvs[i].x).value(type, quad_uvs[i].y).end_record();
    }
    body.list(count_type, index_type, {0, 1, 2, 3}).end_record();
    body.list(count_type, index_type, {3, 2, 1}).end_record();
    return body;
}

std::string quad_elements(std::string_view type, std::string_view count_type = "uchar",
                          std::string_view index_type = "int") {
    std::string text = "element vertex 4\n";
    for (const char* name : {"x", "y", "z", "nx", "ny", "nz", "u", "v"})
        text += "property " + std::string(type) + " " + name + "\n";
    return text + "element face 2\nproperty list " + std::string(count_type) + " " + std::string(index_type) +
           " vertex_indices\n";
}

void check_quad_mesh(const PlyMesh& mesh) {
    CHECK(mesh.positions == quad_positions);
    CHECK(mesh.normals == quad_normals);
    CHECK(mesh.uvs == quad_uvs);
    CHECK(mesh.triangles == quad_triangles);
}

// A header line by line, ready for a CRLF or a truncated variant.
std::string with_crlf(std::string_view text) {
    std::string result;
    for (char c : text) result += c == '\n' ? std::string("\r\n") : std::string(1, c);
    return result;
}

}  // namespace

TEST_CASE("read_ply: positions, normals, uvs and triangles in every format and real type") {
    for (Format format : all_formats) {
        for (const std::string& type : real_type_names) {
            CAPTURE(format_name(format));
            CAPTURE(type);
            const fs::path path = write_ply("quad_" + format_name(format) + "_" + type + ".ply", format,
                                            quad_elements(type), quad_body(format, type));
            check_quad_mesh(read_ply(path));
        }
    }
}

TEST_CASE("read_ply: CRLF line ends, comment and obj_info lines") {
    for (Format format : all_formats) {
        CAPTURE(format_name(format));
        const std::string elements = "comment exported on Windows\nobj_info scanned 2024\n" + quad_elements("float") +
                                     "comment between declarations\n";
        std::string body = quad_body(format, "float").bytes();
        // Only ASCII data is text: binary bytes must reach the reader untouched.
        if (format == Format::ascii) body = with_crlf(body);
        const fs::path path = write_file("crlf_" + format_name(format) + ".ply", with_crlf(header(format, elements)) + body);
        check_quad_mesh(read_ply(path));
    }
}

TEST_CASE("read_ply: every scalar type for vertex coordinates") {
    std::vector<std::string> types = integer_type_names;
    types.insert(types.end(), real_type_names.begin(), real_type_names.end());
    for (Format format : all_formats) {
        for (const std::string& type : types) {
            CAPTURE(format_name(format));
            CAPTURE(type);
            const double sign = is_signed_type(type) ? -1.0 : 1.0;
            const std::vector<glm::dvec3> positions{{1.0, 2.0, 3.0}, {sign * 4.0, 5.0, 6.0}, {7.0, 8.0, sign * 127.0}};
            Body body(format);
            for (const glm::dvec3& p : positions) body.value(type, p.x).value(type, p.y).value(type, p.z).end_record();
            body.list("uchar", "int", {0, 1, 2}).end_record();
            const std::string elements = "element vertex 3\nproperty " + type + " x\nproperty " + type + " y\nproperty " +
                                         type + " z\nelement face 1\nproperty list uchar int vertex_indices\n";
            const PlyMesh mesh = read_ply(write_ply("coordinates_" + format_name(format) + "_" + type + ".ply", format,
                                                   elements, body));
            CHECK(mesh.positions == positions);
            CHECK(mesh.normals.empty());
            CHECK(mesh.uvs.empty());
            CHECK(mesh.triangles == std::vector<Triangle>{{0, 1, 2}});
        }
    }
}

TEST_CASE("read_ply: the extremes of every integer type, signed and unsigned kept apart") {
    struct Extremes {
        const char* type;
        double low, high;
    };
    const std::array<Extremes, 12> all{{{"char", -128, 127},
                                        {"int8", -128, 127},
                                        {"uchar", 0, 255},
                                        {"uint8", 0, 255},
                                        {"short", -32768, 32767},
                                        {"int16", -32768, 32767},
                                        {"ushort", 0, 65535},
                                        {"uint16", 0, 65535},
                                        {"int", -2147483648.0, 2147483647},
                                        {"int32", -2147483648.0, 2147483647},
                                        {"uint", 0, 4294967295.0},
                                        {"uint32", 0, 4294967295.0}}};
    for (Format format : all_formats) {
        for (const auto& limits : all) {
            const char* const type = limits.type;
            const double low = limits.low, high = limits.high;
            CAPTURE(format_name(format));
            CAPTURE(type);
            const std::string name(type);
            const std::vector<glm::dvec3> positions{{low, high, 0.0}, {high, low, 1.0}, {1.0, 1.0, high}};
            Body body(format);
            for (const glm::dvec3& p : positions) body.value(name, p.x).value(name, p.y).value(name, p.z).end_record();
            body.list("uchar", "int", {0, 1, 2}).end_record();
            const std::string elements = "element vertex 3\nproperty " + name + " x\nproperty " + name + " y\nproperty " +
                                         name + " z\nelement face 1\nproperty list uchar int vertex_indices\n";
            const PlyMesh mesh = read_ply(write_ply("extremes_" + format_name(format) + "_" + name + ".ply", format,
                                                   elements, body));
            CHECK(mesh.positions == positions);
        }
    }
}

TEST_CASE("read_ply: ASCII numbers with a leading plus sign and exponents") {
    const PlyMesh mesh = read_ply(write_file(
        "plus_sign.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                         "+1.5 -2 1e3\n\t0.25   +0 -1.25E-2\n7 8 9\n+3 +0 1 +2\n"));
    CHECK(mesh.positions == std::vector<glm::dvec3>{{1.5, -2.0, 1000.0}, {0.25, 0.0, -0.0125}, {7.0, 8.0, 9.0}});
    CHECK(mesh.triangles == std::vector<Triangle>{{0, 1, 2}});
}

TEST_CASE("read_ply: every list count type with every index type") {
    int combinations = 0;
    for (Format format : all_formats) {
        for (const std::string& count_type : integer_type_names) {
            for (const std::string& index_type : integer_type_names) {
                CAPTURE(format_name(format));
                CAPTURE(count_type);
                CAPTURE(index_type);
                const std::string name = "list_" + format_name(format) + "_" + count_type + "_" + index_type + ".ply";
                const PlyMesh mesh = read_ply(write_ply(name, format, quad_elements("float", count_type, index_type),
                                                        quad_body(format, "float", count_type, index_type)));
                check_quad_mesh(mesh);
                ++combinations;
            }
        }
    }
    CHECK(combinations == 3 * 12 * 12);
}

TEST_CASE("read_ply: quads and a pentagon are fanned from their first vertex") {
    for (Format format : all_formats) {
        CAPTURE(format_name(format));
        Body body(format);
        for (int i = 0; i < 7; ++i) body.value("float", i).value("float", i * i).value("float", -i).end_record();
        body.list("uchar", "int", {0, 1, 2, 3}).end_record();
        body.list("uchar", "int", {6, 5, 4, 3, 2}).end_record();
        body.list("uchar", "int", {1, 4, 6}).end_record();
        const std::string elements = "element vertex 7\nproperty float x\nproperty float y\nproperty float z\n"
                                     "element face 3\nproperty list uchar int vertex_indices\n";
        const PlyMesh mesh = read_ply(write_ply("fan_" + format_name(format) + ".ply", format, elements, body));
        CHECK(mesh.positions.size() == 7);
        CHECK(mesh.positions[6] == glm::dvec3(6.0, 36.0, -6.0));
        CHECK(mesh.triangles == std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {6, 5, 4}, {6, 4, 3}, {6, 3, 2}, {1, 4, 6}});
    }
}

TEST_CASE("read_ply: unknown properties, list properties and extra elements are skipped") {
    for (Format format : all_formats) {
        CAPTURE(format_name(format));
        const std::string elements =
            "element material 2\nproperty uchar red\nproperty float shininess\nproperty list ushort double weights\n"
            "element vertex 4\nproperty double confidence\nproperty float x\nproperty list uint short neighbours\n"
            "property float y\nproperty short intensity\nproperty float z\nproperty uchar red\n"
            "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
            "element edge 3\nproperty int vertex1\nproperty int vertex2\nproperty uchar red\n"
            "element face 2\nproperty uchar flags\nproperty list uchar int vertex_indices\n"
            "property list uchar float texcoord\nproperty int material_index\n"
            "element camera 1\nproperty float view_px\nproperty list int char name\n";
        Body body(format);
        body.value("uchar", 255).value("float", 0.5).list("ushort", "double", {1.0, 2.0, 3.0}).end_record();
        body.value("uchar", 0).value("float", 64).list("ushort", "double", {}).end_record();
        for (std::size_t i = 0; i < quad_positions.size(); ++i) {
            body.value("double", 0.99).value("float", quad_positions[i].x);
            body.list("uint", "short", {1, -2, 3}).value("float", quad_positions[i].y);
            body.value("short", -7).value("float", quad_positions[i].z).value("uchar", 200);
            for (int axis = 0; axis < 3; ++axis) body.value("float", quad_normals[i][axis]);
            body.value("float", quad_uvs[i].x).value("float", quad_uvs[i].y).end_record();
        }
        for (int i = 0; i < 3; ++i) body.value("int", i).value("int", i + 1).value("uchar", 9).end_record();
        body.value("uchar", 1).list("uchar", "int", {0, 1, 2, 3}).list("uchar", "float", {0, 0, 1, 0, 1, 1, 0, 1});
        body.value("int", 5).end_record();
        body.value("uchar", 2).list("uchar", "int", {3, 2, 1}).list("uchar", "float", {}).value("int", -1).end_record();
        body.value("float", 1.5).list("int", "char", {99, 97, 109}).end_record();
        check_quad_mesh(read_ply(write_ply("extra_" + format_name(format) + ".ply", format, elements, body)));
    }
}

TEST_CASE("read_ply: face element before the vertex element") {
    for (Format format : all_formats) {
        CAPTURE(format_name(format));
        Body body(format);
        body.list("uchar", "uint", {0, 1, 2, 3}).end_record();
        body.list("uchar", "uint", {3, 2, 1}).end_record();
        for (const glm::dvec3& p : quad_positions) body.value("float", p.x).value("float", p.y).value("float", p.z).end_record();
        const std::string elements = "element face 2\nproperty list uchar uint vertex_indices\n"
                                     "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n";
        const PlyMesh mesh = read_ply(write_ply("face_first_" + format_name(format) + ".ply", format, elements, body));
        CHECK(mesh.positions == quad_positions);
        CHECK(mesh.triangles == quad_triangles);
    }
}

TEST_CASE("read_ply: vertex_index as the name of the index list") {
    for (Format format : all_formats) {
        CAPTURE(format_name(format));
        Body body(format);
        for (const glm::dvec3& p : quad_positions) body.value("float", p.x).value("float", p.y).value("float", p.z).end_record();
        body.list("uint8", "int", {0, 1, 2, 3}).end_record();
        body.list("uint8", "int", {3, 2, 1}).end_record();
        const std::string elements = "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                                     "element face 2\nproperty list uint8 int vertex_index\n";
        const PlyMesh mesh = read_ply(write_ply("vertex_index_" + format_name(format) + ".ply", format, elements, body));
        CHECK(mesh.positions == quad_positions);
        CHECK(mesh.triangles == quad_triangles);
    }
}

TEST_CASE("read_ply: texture coordinate names, and normals only when nx ny nz are all there") {
    const std::array<std::array<const char*, 2>, 4> uv_names{
        {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}}};
    for (Format format : all_formats) {
        for (const auto& names : uv_names) {
            const char* const u_name = names[0];
            const char* const v_name = names[1];
            CAPTURE(format_name(format));
            CAPTURE(u_name);
            Body body(format);
            for (std::size_t i = 0; i < quad_positions.size(); ++i) {
                body.value("float", quad_uvs[i].y).value("float", quad_positions[i].x);
                body.value("float", quad_positions[i].y).value("float", quad_positions[i].z);
                body.value("float", 1.0).value("float", 2.0).value("float", quad_uvs[i].x).end_record();
            }
            body.list("uchar", "int", {0, 1, 2, 3}).end_record();
            body.list("uchar", "int", {3, 2, 1}).end_record();
            // v before u, and nx ny without nz: not a normal.
            const std::string elements = "element vertex 4\nproperty float " + std::string(v_name) +
                                         "\nproperty float x\nproperty float y\nproperty float z\n"
                                         "property float nx\nproperty float ny\nproperty float " + u_name +
                                         "\nelement face 2\nproperty list uchar int vertex_indices\n";
            const PlyMesh mesh = read_ply(
                write_ply("uv_" + format_name(format) + "_" + u_name + ".ply", format, elements, body));
            CHECK(mesh.positions == quad_positions);
            CHECK(mesh.uvs == quad_uvs);
            CHECK(mesh.normals.empty());
            CHECK(mesh.triangles == quad_triangles);
        }
    }
}

TEST_CASE("read_ply: an empty face element gives an empty mesh, not an error") {
    const PlyMesh mesh = read_ply(write_file(
        "empty.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                     "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"));
    CHECK(mesh.positions.empty());
    CHECK(mesh.triangles.empty());
}

namespace {

const std::string triangle_elements = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                      "element face 1\nproperty list uchar int vertex_indices\n";

Body triangle_body(Format format, std::initializer_list<double> indices = {0, 1, 2}) {
    Body body(format);
    body.value("float", 0).value("float", 0).value("float", 0).end_record();
    body.value("float", 1).value("float", 0).value("float", 0).end_record();
    body.value("float", 0).value("float", 1).value("float", 0).end_record();
    return body.list("uchar", "int", indices).end_record();
}

}  // namespace

TEST_CASE("read_ply: the triangle the malformed cases start from is read") {
    for (Format format : all_formats)
        CHECK(read_ply(write_ply("good_" + format_name(format) + ".ply", format, triangle_elements, triangle_body(format)))
                  .triangles.size() == 1);
}

TEST_CASE("read_ply rejects: missing file, not a PLY, broken header") {
    check_rejects(temporary_directory() / "does_not_exist.ply", "", "no such file");
    check_rejects(write_file("empty_file.ply", ""), "header line 1", "not a PLY file");
    check_rejects(write_file("obj_file.ply", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "header line 1", "not a PLY file");
    check_rejects(write_file("plywood.ply", "plywood\nformat ascii 1.0\nend_header\n"), "header line 1", "not a PLY file");
    check_rejects(write_file("unknown_format.ply", "ply\nformat binary_middle_endian 1.0\n" + triangle_elements + "end_header\n"),
                  "header line 2", "unknown format 'binary_middle_endian'");
    check_rejects(write_file("bad_version.ply", "ply\nformat ascii 2.0\n" + triangle_elements + "end_header\n"),
                  "header line 2", "version");
    check_rejects(write_file("no_format.ply", "ply\n" + triangle_elements + "end_header\n"), "header line 8", "no format");
    check_rejects(write_file("unknown_type.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float16 x\n"),
                  "header line 4", "unknown property type 'float16'");
    check_rejects(write_file("unknown_list_type.ply", "ply\nformat ascii 1.0\nelement face 1\n"
                                                      "property list uchar long vertex_indices\nend_header\n"),
                  "header line 4", "unknown property type 'long'");
    check_rejects(write_file("float_count.ply", "ply\nformat ascii 1.0\nelement face 1\n"
                                                "property list float int vertex_indices\nend_header\n"),
                  "header line 4", "integer");
    const std::string no_end = "ply\nformat binary_little_endian 1.0\n" + triangle_elements;
    check_rejects(write_file("no_end_header.ply", no_end), "header line", "no end_header");
    check_rejects(write_file("no_end_header_binary.ply", no_end + std::string("\0\0\0\x3f\xff\n\x01", 7)), "header line",
                  "no end_header");
    check_rejects(write_file("unknown_keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 3\nend_header\n"),
                  "header line 3", "unknown header keyword 'elemnt'");
    check_rejects(write_file("bad_count.ply", "ply\nformat ascii 1.0\nelement vertex -3\nend_header\n"), "header line 3",
                  "'-3'");
    check_rejects(write_file("orphan_property.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n"),
                  "header line 3", "before any element");
    check_rejects(write_file("no_faces.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                             "property float y\nproperty float z\nend_header\n0 0 0\n"),
                  "header", "no face element");
    check_rejects(write_file("float_indices.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                                  "property float y\nproperty float z\nelement face 1\n"
                                                  "property list uchar float vertex_indices\nend_header\n"),
                  "header line 8", "integer type");
}

TEST_CASE("read_ply rejects: a vertex element without x, y or z") {
    for (const char* missing : {"x", "y", "z"}) {
        CAPTURE(missing);
        std::string elements = "element vertex 3\n";
        for (const char* axis : {"x", "y", "z"})
            elements += std::string("property float ") + (axis == std::string_view(missing) ? "w" : axis) + "\n";
        elements += "element face 1\nproperty list uchar int vertex_indices\n";
        for (Format format : all_formats)
            check_rejects(write_ply("missing_" + std::string(missing) + "_" + format_name(format) + ".ply", format,
                                    elements, triangle_body(format)),
                          "element vertex", "no property '" + std::string(missing) + "'");
    }
}

TEST_CASE("read_ply rejects: a header that claims more records than the file holds, quickly") {
    const std::string huge = "element vertex 2147483648\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 1\nproperty list uchar int vertex_indices\n";
    for (Format format : all_formats) {
        CAPTURE(format_name(format));
        const fs::path path = write_ply("huge_" + format_name(format) + ".ply", format, huge, triangle_body(format));
        const auto start = std::chrono::steady_clock::now();
        CHECK_THROWS_AS(read_ply(path), LoadError);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        CHECK(seconds < 0.5);  // no 2^31-element reservation and no 2^31-step loop
        check_rejects(path, "element vertex", "header declares 2147483648 records");
    }
    // 4 vertices promised, 2.5 given: the project's own truncated.ply, in every format.
    const std::string four = "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 2\nproperty list uchar int vertex_indices\n";
    for (Format format : all_formats) {
        Body body(format);
        body.value("float", 0).value("float", 0).value("float", 0).end_record();
        body.value("float", 1).value("float", 0).value("float", 0).end_record();
        body.value("float", 0).value("float", 1);
        check_rejects(write_ply("short_" + format_name(format) + ".ply", format, four, body), "element vertex",
                      "header declares 4 records");
    }
    const std::string faces = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                              "element face 1000000\nproperty list uchar int vertex_indices\n";
    for (Format format : all_formats)
        check_rejects(write_ply("many_faces_" + format_name(format) + ".ply", format, faces, triangle_body(format)),
                      "element face", "header declares 1000000 records");
}

TEST_CASE("read_ply rejects: data truncated in the middle") {
    for (Format format : all_formats) {
        CAPTURE(format_name(format));
        const std::string elements = "element vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
                                     "element face 3\nproperty list uint int vertex_indices\n";
        Body body(format);
        for (int i = 0; i < 4; ++i) body.value("double", 0.1234567 * i).value("double", 1.0 / 3.0).value("double", i).end_record();
        body.list("uint", "int", {0, 1, 2}).end_record();
        body.list("uint", "int", {1, 2, 3}).end_record();
        body.list("uint", "int", {2, 3, 0}).end_record();
        const std::string& full = body.bytes();
        CHECK(read_ply(write_ply("whole_" + format_name(format) + ".ply", format, elements, body)).triangles.size() == 3);
        // Cut inside the second face, then inside the third vertex.
        const std::size_t in_second_face = format == Format::ascii ? full.size() - 14 : 4 * 24 + 16 + 6;
        const std::size_t in_third_vertex = format == Format::ascii ? full.find('\n', full.find('\n') + 1) + 5 : 2 * 24 + 8 + 3;
        check_rejects(write_ply("cut_face_" + format_name(format) + ".ply", format, elements,
                                Body(format).raw(full.substr(0, in_second_face))),
                      "element face 1", "list count 3 exceeds the remaining data");
        const fs::path cut_vertex = write_ply("cut_vertex_" + format_name(format) + ".ply", format, elements,
                                              Body(format).raw(full.substr(0, in_third_vertex)));
        // ASCII records have no fixed size, so only the read itself finds the end.
        if (format == Format::ascii) check_rejects(cut_vertex, "element vertex 2", "unexpected end of file");
        else check_rejects(cut_vertex, "element vertex", "header declares 4 records");
    }
    // Binary: the vertex records are whole, the first face ends after its count and two indices.
    Body body(Format::binary_little_endian);
    for (int i = 0; i < 3; ++i) body.value("float", i).value("float", 0).value("float", 0);
    body.value("uchar", 3).value("int", 0).value("int", 1);
    check_rejects(write_ply("cut_indices.ply", Format::binary_little_endian, triangle_elements, body), "element face 0",
                  "exceeds the remaining data");
    // Binary: the last face's indices are whole, the property after them is cut.
    const std::string with_material = triangle_elements + "property int material\n";
    Body cut_material(Format::binary_little_endian);
    for (int i = 0; i < 3; ++i) cut_material.value("float", i).value("float", 0).value("float", 0);
    cut_material.list("uchar", "int", {0, 1, 2}).raw(std::string(2, '\0'));
    check_rejects(write_ply("cut_material.ply", Format::binary_little_endian, with_material, cut_material),
                  "element face 0", "unexpected end of data (byte " +
                      std::to_string(header(Format::binary_little_endian, with_material).size() + 3 * 12 + 13) + ")");
}

TEST_CASE("read_ply rejects: non-numeric ASCII values") {
    auto write_text = [](const std::string& name, const std::string& data) {
        return write_file(name, header(Format::ascii, triangle_elements) + data);
    };
    check_rejects(write_text("word.ply", "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"), "element vertex 1",
                  "'zero' is not a number (line 11)");
    check_rejects(write_text("trailing.ply", "0 0 0\n1 0 0\n0 1x 0\n3 0 1 2\n"), "element vertex 2", "'1x' is not a number");
    check_rejects(write_text("real_index.ply", "0 0 0\n1 0 0\n0 1 0\n3 0 1.0 2\n"), "element face 0",
                  "'1.0' is not an integer");
    check_rejects(write_text("real_count.ply", "0 0 0\n1 0 0\n0 1 0\n3.0 0 1 2\n"), "element face 0",
                  "'3.0' is not an integer");
    check_rejects(write_text("too_large.ply", "0 0 0\n1e400 0 0\n0 1 0\n3 0 1 2\n"), "element vertex 1", "out of range");
}

TEST_CASE("read_ply rejects: face indices out of range") {
    for (Format format : all_formats) {
        CAPTURE(format_name(format));
        check_rejects(write_ply("index_negative_" + format_name(format) + ".ply", format, triangle_elements,
                                triangle_body(format, {0, -1, 2})),
                      "element face 0", "vertex index -1 out of range [0, 3)");
        check_rejects(write_ply("index_too_large_" + format_name(format) + ".ply", format, triangle_elements,
                                triangle_body(format, {0, 1, 3})),
                      "element face 0", "vertex index 3 out of range [0, 3)");
    }
    // uint indices beyond int32: must not wrap to a valid index.
    const std::string uint_elements = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                      "element face 1\nproperty list uchar uint vertex_indices\n";
    Body body(Format::binary_big_endian);
    for (int i = 0; i < 3; ++i) body.value("float", i).value("float", 1).value("float", 2);
    body.list("uchar", "uint", {0, 1, 4294967295.0});
    check_rejects(write_ply("index_uint_max.ply", Format::binary_big_endian, uint_elements, body), "element face 0",
                  "vertex index 4294967295 out of range");
}

TEST_CASE("read_ply rejects: faces with fewer than 3 indices") {
    for (Format format : all_formats) {
        CAPTURE(format_name(format));
        check_rejects(write_ply("two_indices_" + format_name(format) + ".ply", format, triangle_elements,
                                triangle_body(format, {0, 1})),
                      "element face 0", "face has 2 vertex indices, at least 3 needed");
        check_rejects(write_ply("no_indices_" + format_name(format) + ".ply", format, triangle_elements,
                                triangle_body(format, {})),
                      "element face 0", "face has 0 vertex indices");
    }
    const std::string char_count = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                   "element face 1\nproperty list char int vertex_indices\n";
    Body body(Format::binary_little_endian);
    for (int i = 0; i < 3; ++i) body.value("float", i).value("float", 1).value("float", 2);
    body.value("char", -3).value("int", 0).value("int", 1).value("int", 2);
    check_rejects(write_ply("negative_count.ply", Format::binary_little_endian, char_count, body), "element face 0",
                  "face has -3 vertex indices");
}

TEST_CASE("read_ply rejects: NaN and infinite vertex values") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double infinity = std::numeric_limits<double>::infinity();
    for (Format format : all_formats) {
        for (const std::string& type : real_type_names) {
            for (double bad : {nan, infinity, -infinity}) {
                CAPTURE(format_name(format));
                CAPTURE(type);
                CAPTURE(bad);
                const std::string elements = "element vertex 3\nproperty " + type + " x\nproperty " + type +
                                             " y\nproperty " + type + " z\nelement face 1\n"
                                             "property list uchar int vertex_indices\n";
                Body body(format);
                body.value(type, 0).value(type, 0).value(type, 0).end_record();
                body.value(type, 0).value(type, 0).value(type, 0).end_record();
                body.value(type, 0).value(type, 1).value(type, bad).end_record();
                body.list("uchar", "int", {0, 1, 2}).end_record();
                check_rejects(write_ply("non_finite_" + format_name(format) + "_" + type + ".ply", format, elements, body),
                              "element vertex 2", "non-finite coordinate");
            }
        }
    }
    check_rejects(write_ply("nan_normal.ply", Format::ascii,
                            "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n"
                            "property float ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\n",
                            Body(Format::ascii).raw("0 0 0 nan 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n")),
                  "element vertex 0", "non-finite normal");
}

TEST_CASE("read_ply rejects: list counts far beyond the remaining data") {
    for (Format format : {Format::binary_little_endian, Format::binary_big_endian}) {
        CAPTURE(format_name(format));
        const std::string elements = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                     "element face 1\nproperty list uint int vertex_indices\n";
        Body body(format);
        for (int i = 0; i < 3; ++i) body.value("float", i).value("float", 1).value("float", 2);
        body.value("uint", 4294967280.0).value("int", 0).value("int", 1).value("int", 2);
        check_rejects(write_ply("huge_list_" + format_name(format) + ".ply", format, elements, body), "element face 0",
                      "list count 4294967280 exceeds the remaining data");
        // The same in a list the reader skips.
        const std::string skipped = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                                    "property list int double history\nelement face 0\n"
                                    "property list uchar int vertex_indices\n";
        Body skipped_body(format);
        skipped_body.value("float", 0).value("float", 1).value("float", 2).value("int", 2000000000);
        check_rejects(write_ply("huge_skipped_list_" + format_name(format) + ".ply", format, skipped, skipped_body),
                      "element vertex 0", "list count 2000000000 exceeds the remaining data");
    }
    check_rejects(write_file("huge_list_ascii.ply",
                             header(Format::ascii, triangle_elements) + "0 0 0\n1 0 0\n0 1 0\n1000000000 0 1 2\n"),
                  "element face 0", "list count 1000000000 exceeds the remaining data");
}

TEST_CASE("read_ply: the course's real meshes") {
    const fs::path shared = PRISM_SHARED_DIR;
    if (!fs::is_directory(shared / "meshes") || !fs::is_directory(shared / "ceng795")) {
        MESSAGE("skipped: no shared data (meshes/ and ceng795/) at " << shared);
        return;
    }
    const PlyMesh bunny = read_ply(shared / "meshes/stanford_bunny_bun_zipper.ply");
    CHECK(bunny.triangles.size() == 69451);
    CHECK(bunny.positions.size() == 35947);
    const PlyMesh dragon = read_ply(shared / "meshes/stanford_dragon_vrip_res3.ply");
    CHECK(dragon.triangles.size() == 47794);
    CHECK(dragon.positions.size() == 22998);
    CHECK(dragon.normals.size() == dragon.positions.size());

    int files = 0;
    std::uintmax_t largest_size = 0;
    fs::path largest;
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(shared / "ceng795")) {
        if (!entry.is_regular_file() || entry.path().extension() != ".ply") continue;
        CAPTURE(entry.path());
        const PlyMesh mesh = read_ply(entry.path());
        CHECK(mesh.triangles.size() >= 1);
        CHECK((mesh.normals.empty() || mesh.normals.size() == mesh.positions.size()));
        CHECK((mesh.uvs.empty() || mesh.uvs.size() == mesh.positions.size()));
        const bool in_range = std::all_of(mesh.triangles.begin(), mesh.triangles.end(), [&](const Triangle& t) {
            return std::all_of(t.begin(), t.end(), [&](std::uint32_t i) { return i < mesh.positions.size(); });
        });
        CHECK(in_range);
        ++files;
        if (entry.file_size() > largest_size) {
            largest_size = entry.file_size();
            largest = entry.path();
        }
    }
    CHECK(files > 0);
    if (!largest.empty()) {
        const auto start = std::chrono::steady_clock::now();
        const PlyMesh mesh = read_ply(largest);
        const double milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        MESSAGE("read " << files << " ceng795 PLY files; largest " << fs::relative(largest, shared).string() << " ("
                        << largest_size << " bytes, " << mesh.triangles.size() << " triangles) in " << milliseconds
                        << " ms");
    }
}
