// Hostile input (issue 12): the limits a scene file may not pass, element trees and instance chains
// no file can make overflow the stack, outputs confined to their folder, and every input the
// fuzzers found (tests/data/fuzz/TARGET/) replayed through the reader it broke.
#include "temporary_folder.hpp"
#include "text_contains.hpp"

#include <prism/image/decoder_guard.hpp>
#include <prism/image/image_io.hpp>
#include <prism/io/json_reader.hpp>
#include <prism/io/limits.hpp>
#include <prism/io/load.hpp>
#include <prism/io/load_error.hpp>
#include <prism/io/output_path.hpp>
#include <prism/io/ply.hpp>
#include <prism/io/read_file.hpp>
#include <prism/io/scene_loader.hpp>
#include <prism/io/xml_reader.hpp>

#include <doctest/doctest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

using prism_test::contains;

#ifndef PRISM_SOURCE_DIR
#define PRISM_SOURCE_DIR "."
#endif

namespace {

using prism::io::LoadError;

// tests/data/good.xml with `extra` inserted after <Scene> and `camera_extra` after its ImageName.
std::string scene_text(const std::string& extra, const std::string& camera_extra = {}) {
    std::ifstream stream(std::filesystem::path(PRISM_SOURCE_DIR) / "tests/data/good.xml");
    std::string text((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
    REQUIRE(!text.empty());
    text.insert(text.find("<Scene>") + 7, extra);
    const std::string image_name = "<ImageName>out.png</ImageName>";
    text.insert(text.find(image_name) + image_name.size(), camera_extra);
    return text;
}

prism::scene::Scene load_text(const std::string& text, const prism::io::LoadOptions& options = {}) {
    return prism::io::interpret_scene(prism::io::parse_xml(text, "scene.xml"), "scene.xml", options);
}

// The message of the LoadError `load` throws, or "" when it throws none.
std::string refusal(const std::function<void()>& load) {
    try {
        load();
    } catch (const LoadError& error) {
        return error.what();
    }
    return "";
}

}  // namespace

TEST_CASE("MaxRecursionDepth: up to 64 by default, up to the option's value, never past the stack-safe depth") {
    const auto depth = [](int value) { return "<MaxRecursionDepth>" + std::to_string(value) + "</MaxRecursionDepth>"; };
    CHECK(load_text(scene_text(depth(64))).max_recursion_depth == 64);
    const std::string over = refusal([&] { load_text(scene_text(depth(65))); });
    CHECK(contains(over, "<MaxRecursionDepth>"));
    CHECK(contains(over, "limit of 64"));

    prism::io::LoadOptions raised;
    raised.limits.max_recursion_depth = 300;
    CHECK(load_text(scene_text(depth(300)), raised).max_recursion_depth == 300);
    CHECK(contains(refusal([&] { load_text(scene_text(depth(301)), raised); }), "limit of 300"));

    // An option past the stack-safe depth (only a program can set one) still stops there.
    raised.limits.max_recursion_depth = 1 << 30;
    const int safe = prism::io::stack_safe_recursion_depth;
    CHECK(load_text(scene_text(depth(safe)), raised).max_recursion_depth == safe);
    CHECK(contains(refusal([&] { load_text(scene_text(depth(safe + 1)), raised); }), "limit of " + std::to_string(safe)));
}

TEST_CASE("ImageResolution and NumSamples past prism's limits are refused, naming the element") {
    const auto resolution = [](const std::string& size) {
        std::string text = scene_text("");
        const std::string written = "<ImageResolution>16 16</ImageResolution>";
        return text.replace(text.find(written), written.size(), "<ImageResolution>" + size + "</ImageResolution>");
    };
    const std::int64_t side = prism::io::max_image_side;
    CHECK(load_text(resolution(std::to_string(side) + " 16")).cameras.at(0).width == side);
    CHECK(contains(refusal([&] { load_text(resolution(std::to_string(side + 1) + " 16")); }), "<ImageResolution>"));
    CHECK(contains(refusal([&] { load_text(resolution("200000 200000")); }), "<ImageResolution>"));
    // Each side within the limit, the product not.
    CHECK(contains(refusal([&] { load_text(resolution("12000 12000")); }), "over prism's limits"));

    const auto samples = [](std::int64_t count) { return "<NumSamples>" + std::to_string(count) + "</NumSamples>"; };
    CHECK(load_text(scene_text("", samples(prism::io::max_samples_per_pixel))).cameras.at(0).num_samples ==
          prism::io::max_samples_per_pixel);
    const std::string over = refusal([&] { load_text(scene_text("", samples(2000000000))); });
    CHECK(contains(over, "<NumSamples>"));
    CHECK(contains(over, "limit of " + std::to_string(prism::io::max_samples_per_pixel)));
}

TEST_CASE("meshes that would need more memory to render than the limit are refused at the mesh") {
    prism::io::LoadOptions options;
    // The camera's 16 x 16 film and one triangle's worth.
    options.limits.memory_bytes = 16 * 16 * prism::io::film_bytes_per_pixel + prism::io::render_bytes_per_triangle;
    CHECK(load_text(scene_text(""), options).meshes.size() == 1);
    std::string two = scene_text("");
    const std::string mesh = "<Mesh id=\"1\"><Material>1</Material><Faces>1 2 3</Faces></Mesh>";
    two.insert(two.find(mesh) + mesh.size(), "<Mesh id=\"2\"><Material>1</Material><Faces>3 2 1</Faces></Mesh>");
    const std::string message = refusal([&] { load_text(two, options); });
    CHECK(contains(message, "<Mesh id=\"2\">"));
    CHECK(contains(message, "2 triangles"));
    CHECK(prism::io::physical_memory_bytes() > 0);
}

// Texture images count with the meshes against the same limit, weighed from their headers before
// they are decoded: each image may be within the image limits and still, with enough of them,
// pass the machine's memory (a few hundred kB of PNG holds 2^26 texels of one colour).
TEST_CASE("texture images that would need more memory than the limit are refused at the image, undecoded") {
    const prism_test::TemporaryFolder folder;
    prism::write_image(folder.path() / "a.png", prism::Image(512, 512));
    prism::write_image(folder.path() / "b.png", prism::Image(512, 512));
    const std::uint64_t image = prism::io::texture_bytes(512 * 512, 3);
    REQUIRE(image == std::uint64_t(1) << 20);
    const std::uint64_t film = 16 * 16 * prism::io::film_bytes_per_pixel, triangle = prism::io::render_bytes_per_triangle;
    const auto load = [&](const std::string& images, std::uint64_t limit) {
        prism::io::LoadOptions options;
        options.limits.memory_bytes = limit;
        const std::filesystem::path scene =
            folder.write("scene.xml", scene_text("<Textures><Images>" + images + "</Images></Textures>"));
        return refusal([&] { (void)prism::io::load_scene(scene, options); });
    };
    const std::string one = "<Image id=\"1\">a.png</Image>", two = one + "<Image id=\"2\">b.png</Image>";
    // Within the limit: two images (decoded side by side) and the mesh's triangle.
    CHECK(load(two, 2 * image + film + triangle) == "");
    // The second image passes it: refused there, naming its file.
    std::string message = load(two, image + film + triangle);
    CHECK(contains(message, "<Image id=\"2\">"));
    CHECK(contains(message, "b.png: the scene's textures reach 2 MiB here (this one 512 x 512): about 2 MiB to render "
                            "(meshes 0 MiB, textures 2 MiB, films 0 MiB)"));
    // The only image (decoded alone), one byte over.
    message = load(one, image - 1);
    CHECK(contains(message, "<Image id=\"1\">"));
    CHECK(contains(message, "a.png: the scene's textures reach 1 MiB here"));
    // The image fits, the mesh after it does not: the mesh is refused, with the images counted.
    message = load(one, image + film + triangle - 1);
    CHECK(contains(message, "<Mesh id=\"1\">"));
    CHECK(contains(message, "1 triangles here: about 1 MiB to render (meshes 0 MiB, textures 1 MiB"));
}

// Every camera's film is kept until all are rendered: many cameras of the largest resolution
// allowed could pass the machine's memory.
TEST_CASE("cameras whose films would need more memory than the limit are refused at the resolution") {
    std::string two = scene_text("");
    const std::string second = "<Camera id=\"2\"><Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>"
                               "<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance>"
                               "<ImageResolution>512 512</ImageResolution><ImageName>two.png</ImageName></Camera>";
    two.insert(two.find("</Cameras>"), second);
    const std::uint64_t films = (16 * 16 + 512 * 512) * prism::io::film_bytes_per_pixel;
    prism::io::LoadOptions options;
    options.limits.memory_bytes = films + prism::io::render_bytes_per_triangle;
    CHECK(load_text(two, options).cameras.size() == 2);
    options.limits.memory_bytes = films - 1;
    const std::string message = refusal([&] { load_text(two, options); });
    CHECK(contains(message, "<Camera id=\"2\">/<ImageResolution>"));
    CHECK(contains(message, "the scene's films reach 3 MiB here (this one 512 x 512): about 3 MiB to render"));
}

TEST_CASE("a Perlin texture's NumOctaves past the limit is refused (each is a noise evaluation a lookup)") {
    const auto perlin = [](const std::string& octaves) {
        return scene_text("<Textures><TextureMap id=\"1\" type=\"perlin\"><DecalMode>replace_kd</DecalMode>"
                          "<NumOctaves>" + octaves + "</NumOctaves></TextureMap></Textures>");
    };
    CHECK(load_text(perlin(std::to_string(prism::io::max_noise_octaves))).textures.size() == 1);
    for (const std::string& over : {std::to_string(prism::io::max_noise_octaves + 1), std::string("2147483647")}) {
        const std::string message = refusal([&] { load_text(perlin(over)); });
        CHECK(contains(message, "<NumOctaves>"));
        CHECK(contains(message, over + " is over prism's limit of " + std::to_string(prism::io::max_noise_octaves)));
    }
}

TEST_CASE("an object's texture list past the limit is refused (each is applied at every shading point)") {
    const auto textured = [](std::size_t count) {
        std::string list;
        for (std::size_t i = 0; i < count; ++i) list += (i > 0 ? " 1" : "1");
        std::string text = scene_text("<Textures><TextureMap id=\"1\" type=\"perlin\"><DecalMode>replace_kd</DecalMode>"
                                      "</TextureMap></Textures>");
        text.insert(text.find("<Faces>"), "<Textures>" + list + "</Textures>");
        return text;
    };
    CHECK(load_text(textured(prism::io::max_textures_per_object)).meshes.at(0).textures.size() ==
          prism::io::max_textures_per_object);
    for (const std::size_t over : {prism::io::max_textures_per_object + 1, std::size_t(100000)}) {
        const std::string message = refusal([&] { load_text(textured(over)); });
        CHECK(contains(message, "<Mesh id=\"1\">/<Textures>"));
        CHECK(contains(message, "more than 64 textures for one object, prism's limit"));
    }
}

TEST_CASE("200,000 nested elements are refused in XML and JSON, without recursion that deep") {
    const int depth = 200000;
    std::string nested;
    for (int i = 0; i < depth; ++i) nested += "<Group>";
    for (int i = 0; i < depth; ++i) nested += "</Group>";
    const std::string xml = refusal([&] { load_text(scene_text(nested)); });
    CHECK(contains(xml, "<Group>"));
    CHECK(contains(xml, "nest more than " + std::to_string(prism::io::max_element_depth)));

    std::string json = "{\"Scene\": ";
    for (int i = 0; i < depth; ++i) json += "{\"Group\": ";
    json += "\"x\"" + std::string(std::size_t(depth) + 1, '}');
    const std::string message = refusal([&] { prism::io::parse_json(json, "scene.json"); });
    CHECK(contains(message, "<Group>/.../<Group>"));
    CHECK(contains(message, "nest more than " + std::to_string(prism::io::max_element_depth)));

    // The deepest tree allowed is read.
    std::string deepest = "<Scene>";
    for (int i = 1; i < prism::io::max_element_depth; ++i) deepest += "<Group>";
    for (int i = 1; i < prism::io::max_element_depth; ++i) deepest += "</Group>";
    CHECK(prism::io::parse_xml(deepest + "</Scene>", "scene.xml").children.size() == 1);
}

// Elements and attributes cost some 200 bytes each to read, 40-60 times their size in the file, so
// they are counted before the tree is built (XML: before pugixml builds its own) and a file past
// max_scene_nodes is refused: 16 million `<a/>` (64 MB) took 3.6 GB to read before.
TEST_CASE("a scene file's elements and attributes are counted and refused past the limit") {
    const auto nodes_refused = [](const std::string& message, std::uint64_t limit) {
        return contains(message, "the file holds more than " + std::to_string(limit) + " elements and attributes");
    };
    SUBCASE("XML: start tags and their attributes count; end tags, comments, CDATA and declarations do not") {
        // 9 nodes: Scene, Objects, Sphere and its id, Material, Center, Radius, Group and its attribute
        // (one, though its value holds '=').
        const std::string text =
            "<?xml version=\"1.0\"?>\n<!DOCTYPE Scene>\n<Scene><!-- <a/><b/> -->\n<Objects>\n"
            "<Sphere id=\"1\"><Material>1</Material><Center>1</Center><Radius><![CDATA[<c/>]]>1</Radius></Sphere>\n"
            "</Objects><Group name='a=b'/></Scene>";
        CHECK(prism::io::parse_xml(text, "scene.xml", 9).children.size() == 2);
        CHECK(nodes_refused(refusal([&] { prism::io::parse_xml(text, "scene.xml", 8); }), 8));
        // The seventh node, Radius, passes a limit of 6: named inside the elements still open, at its line.
        const std::string message = refusal([&] { prism::io::parse_xml(text, "scene.xml", 6); });
        CHECK(contains(message, "scene.xml: <Objects>/<Sphere id=\"1\"> (line 5): "));
        CHECK(nodes_refused(message, 6));
    }
    SUBCASE("XML at prism's limit: refused before any tree is built") {
        std::string text = "<Scene>";
        text.reserve(4 * std::size_t(prism::io::max_scene_nodes) + 16);
        for (std::uint64_t i = 1; i < prism::io::max_scene_nodes; ++i) text += "<a/>";
        CHECK(prism::io::detail::xml::where_nodes_pass(text, prism::io::max_scene_nodes) == std::string::npos);
        text += "<a/></Scene>";
        const std::string message = refusal([&] { prism::io::parse_xml(text, "scene.xml"); });
        CHECK(contains(message, "scene.xml: <Scene> (line 1): "));
        CHECK(nodes_refused(message, prism::io::max_scene_nodes));
    }
    SUBCASE("JSON: objects, values and attributes count; the document around the root does not") {
        // 7 nodes: Scene, Objects, Sphere, its _id, Material, and the two Radius values of an array.
        const std::string text = R"({"Scene": {"Objects": {"Sphere": {"_id": "1", "Material": "1"}}, "Radius": ["1", "2"]}})";
        CHECK(prism::io::parse_json(text, "scene.json", 7).children.size() == 3);
        const std::string message = refusal([&] { prism::io::parse_json(text, "scene.json", 6); });
        CHECK(contains(message, "scene.json: <Scene>: "));
        CHECK(nodes_refused(message, 6));
        CHECK(nodes_refused(refusal([&] { prism::io::parse_json(text, "scene.json", 3); }), 3));
    }
}

TEST_CASE("a chain of 20,000 MeshInstances, each naming the next, resolves without recursion") {
    // Written from the end of the chain back to the mesh: each instance's base comes after it.
    const int count = 20000;
    std::string instances;
    for (int i = count; i >= 2; --i)
        instances += "<MeshInstance id=\"" + std::to_string(i) + "\" baseMeshId=\"" + std::to_string(i > 2 ? i - 1 : 1) +
                     "\"><Transformations>t1</Transformations></MeshInstance>";
    std::string text = scene_text("<Transformations><Translation id=\"1\">1 0 0</Translation></Transformations>");
    const std::string mesh = "<Mesh id=\"1\"><Material>1</Material><Faces>1 2 3</Faces></Mesh>";
    text.insert(text.find(mesh) + mesh.size(), instances);
    const prism::scene::Scene scene = load_text(text);
    REQUIRE(scene.mesh_instances.size() == std::size_t(count - 1));
    // The first written is the last of the chain: count - 1 translations by 1 along x.
    CHECK(scene.mesh_instances.front().id == std::to_string(count));
    CHECK(scene.mesh_instances.front().base_mesh == 0);
    CHECK(scene.mesh_instances.front().transform[3][0] == doctest::Approx(count - 1));
    CHECK(scene.mesh_instances.back().transform[3][0] == doctest::Approx(1));

    std::string cycle = scene_text("");
    cycle.insert(cycle.find(mesh) + mesh.size(),
                 "<MeshInstance id=\"2\" baseMeshId=\"3\"/><MeshInstance id=\"3\" baseMeshId=\"4\"/>"
                 "<MeshInstance id=\"4\" baseMeshId=\"2\"/>");
    CHECK(contains(refusal([&] { load_text(cycle); }), "form a cycle"));
}

TEST_CASE("confined_output_path: image names stay inside the output folder") {
    const prism_test::TemporaryFolder folder;
    const std::filesystem::path out = folder.path() / "out";
    std::filesystem::create_directories(out);
    const auto place = [&](const std::string& name) {
        return prism::io::confined_output_path(out, name, "scene.xml", "<Camera id=\"1\">/<ImageName>");
    };
    CHECK(place("image.png") == out / "image.png");
    CHECK(place("renders/./image.png") == out / "renders/image.png");
    CHECK(place("renders/../image.png") == out / "image.png");

    for (const std::string name : {"/tmp/image.png", "../image.png", "renders/../../image.png", "..", "renders/.."}) {
        CAPTURE(name);
        const std::string message = refusal([&] { place(name); });
        CHECK(contains(message, "scene.xml"));
        CHECK(contains(message, "<ImageName>"));
    }

    // Links: one that stays inside is followed, one that leaves or points nowhere is refused.
    std::filesystem::create_directories(out / "inside");
    std::filesystem::create_directories(folder.path() / "outside");
    std::filesystem::create_directory_symlink(out / "inside", out / "to_inside");
    std::filesystem::create_directory_symlink(folder.path() / "outside", out / "to_outside");
    std::filesystem::create_directory_symlink(folder.path() / "nowhere", out / "dangling");
    CHECK(place("to_inside/image.png") == out / "to_inside/image.png");
    CHECK(contains(refusal([&] { place("to_outside/image.png"); }), "through a link"));
    CHECK(contains(refusal([&] { place("dangling/image.png"); }), "points nowhere"));

    // Names the file system cannot hold are refused as such, quoted by their two ends.
    const std::string long_part = refusal([&] { place(std::string(300, 'a') + ".png"); });
    CHECK(contains(long_part, "\"" + std::string(120, 'a') + "..." + std::string(56, 'a') + ".png\" cannot be written under "
                              "--output-dir: a part of it is longer than the 255 bytes of a file name"));
    std::string deep;
    for (int i = 0; i < 3000; ++i) deep += "d/";
    const std::string long_path = refusal([&] { place(deep + "image.png"); });
    CHECK(contains(long_path, "cannot be written under --output-dir: the path is longer than the 4095 bytes of a path"));
    // The longest name a file may have is written, through a temporary file of a name as long.
    const std::string longest = std::string(251, 'a') + ".png";
    CHECK(place(longest) == out / longest);
    prism::write_image(out / longest, prism::Image(1, 1));
    CHECK(std::filesystem::file_size(out / longest) > 0);
    // No temporary file is left beside it: the folder holds the four links and folders and the image.
    CHECK(std::distance(std::filesystem::directory_iterator(out), std::filesystem::directory_iterator()) == 5);
    CHECK(long_path.size() < 400);
}

// prism prepares --output-dir before the render: a folder it cannot write in was found only when
// the first image was written, after every camera had rendered.
TEST_CASE("prepare_output_folder: created when missing, refused with the system's reason when unusable") {
    const prism_test::TemporaryFolder folder;
    const std::filesystem::path nested = folder.path() / "new/renders";
    prism::io::prepare_output_folder(nested);
    CHECK(std::filesystem::is_directory(nested));
    CHECK(std::filesystem::is_empty(nested));  // the probe file is gone
    prism::io::prepare_output_folder(nested);  // an existing folder is fine

    const std::filesystem::path file = folder.write("file.png", "x");
    CHECK(refusal([&] { prism::io::prepare_output_folder(file); }) ==
          file.string() + ": cannot create the output folder: Not a directory");
    CHECK(refusal([&] { prism::io::prepare_output_folder(file / "sub"); }) ==
          (file / "sub").string() + ": cannot create the output folder: Not a directory");
    CHECK(std::filesystem::file_size(file) == 1);
    // Without write permission (root writes anywhere, so only checked for another user).
    if (::geteuid() != 0) {
        const std::filesystem::path locked = folder.path() / "locked";
        std::filesystem::create_directory(locked);
        std::filesystem::permissions(locked, std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
        CHECK(refusal([&] { prism::io::prepare_output_folder(locked); }) ==
              locked.string() + ": cannot write images in the output folder: Permission denied");
        std::filesystem::permissions(locked, std::filesystem::perms::owner_all);
    }
}

TEST_CASE("decode_image refuses an image past the size limits before decoding it") {
    // A PNG header that claims 12000 x 12000 pixels (144 million, over 2^27) and holds none.
    const std::string signature = "\x89PNG\r\n\x1a\n";
    std::string header = std::string("\0\0\0\x0dIHDR", 8) + std::string("\0\0\x2e\xe0\0\0\x2e\xe0\x08\x02\0\0\0", 13);
    header += std::string("\0\0\0\0", 4);  // CRC: stb does not check it
    const std::string message = refusal([&] { prism::decode_image(signature + header, "huge.png"); });
    CHECK(contains(message, "huge.png"));
    CHECK(contains(message, "12000 x 12000"));
    // The same header under a lower cap, as the image fuzzer sets it.
    CHECK(contains(refusal([&] { prism::decode_image(signature + header, "huge.png", 1 << 16); }), "65536 in all"));
    // A texture's decoder (bytes kept) refuses it alike.
    CHECK(refusal([&] { prism::decode_texels(signature + header, "huge.png"); }) == message);
}

TEST_CASE("decode_image: a file's content must be the format its name says; JPEG Huffman tables fit") {
    const std::string png_signature = "\x89PNG\r\n\x1a\n";
    CHECK(prism::detail::has_signature_of(png_signature + "rest", ".png"));
    CHECK(!prism::detail::has_signature_of(png_signature + "rest", ".jpg"));
    CHECK(!prism::detail::has_signature_of("GIF89a", ".tga"));
    CHECK(!prism::detail::has_signature_of("\xFF\xFF\xFF\xD8\xFF\xE0", ".tga"));  // a JPEG after fill bytes
    CHECK(prism::detail::has_signature_of(std::string("\0\0\x02\0", 4), ".tga"));
    CHECK(contains(refusal([&] { prism::decode_image(png_signature + "rest", "photo.jpg"); }), "not the jpg image"));
    CHECK(contains(refusal([&] { prism::decode_image("GIF89a......", "photo.png"); }), "not the png image"));

    // SOI, then one DHT segment holding one table whose 16 counts add up to `codes`.
    const auto jpeg_with_table = [](int codes) {
        std::string table = "\x10";  // an AC table, number 0
        for (int k = 0; k < 16; ++k) table += char(k < codes / 255 ? 255 : k == codes / 255 ? codes % 255 : 0);
        table += std::string(std::size_t(codes), '\x01');
        const std::size_t length = table.size() + 2;
        return std::string("\xFF\xD8\xFF\xC4") + char(length >> 8) + char(length & 0xFF) + table + "\xFF\xD9";
    };
    CHECK(prism::detail::jpeg_huffman_tables_fit(jpeg_with_table(256)));
    CHECK(!prism::detail::jpeg_huffman_tables_fit(jpeg_with_table(257)));
    CHECK(contains(refusal([&] { prism::decode_image(jpeg_with_table(700), "table.jpg"); }), "Huffman table"));

    CHECK(prism::detail::pnm_header_fits("P6\n# a comment 99999999999\n2147483647 1\n255\n"));
    CHECK(!prism::detail::pnm_header_fits("P6\n2147483648 1\n255\n"));
    CHECK(!prism::detail::pnm_header_fits("P5 1 1 # c\n 99999999999 "));
    CHECK(!prism::detail::pnm_header_fits("P5 552 2 5252\n"));  // 16-bit samples
    CHECK(contains(refusal([&] { prism::decode_image("P6 1 99999999999 255\n", "big.ppm"); }), "PNM header"));

    // A texture's decoder, which keeps an 8-bit file's bytes, makes the same checks with the same
    // messages, and refuses what decode_image refuses by format.
    for (const auto& input : std::vector<std::pair<std::string, std::string>>{
             {png_signature + "rest", "photo.jpg"},
             {"GIF89a......", "photo.png"},
             {jpeg_with_table(700), "table.jpg"},
             {"P6 1 99999999999 255\n", "big.ppm"},
             {"GIF89a......", "photo.gif"},
             {"#?RADIANCE\nbroken", "sky.hdr"}}) {
        // Not a structured binding: clang 14 cannot capture one in a lambda.
        const std::string& bytes = input.first;
        const std::string& name = input.second;
        CAPTURE(name);
        const std::string expected = refusal([&] { prism::decode_image(bytes, name); });
        CHECK(!expected.empty());
        CHECK(refusal([&] { prism::decode_texels(bytes, name); }) == expected);
    }
}

// Every input a fuzzer found, replayed through the reader it broke: each must now load or be refused
// with a LoadError (a crash or a sanitizer report fails the test run).
// Every reader (scenes, PLYs, binary data, images) takes its file through io::read_regular_file.
// A named pipe is refused before it is opened (opening it waits for a writer: `prism pipe.xml`
// hung), and a device before it is read (a scene that was a link to /dev/zero grew until the
// memory ran out).
TEST_CASE("read_regular_file: a regular file's bytes; no pipe, device or folder is opened") {
    const prism_test::TemporaryFolder folder;
    const auto refused = [](const std::filesystem::path& path, std::string_view kind, const std::string& why) {
        try {
            (void)prism::io::read_regular_file(path, "<Image id=\"1\">", kind);
        } catch (const LoadError& error) {
            CHECK(std::string(error.what()) == path.string() + ": <Image id=\"1\">: " + why);
            return;
        }
        FAIL("read " << path.string());
    };
    SUBCASE("every byte of a regular file, and an empty one") {
        std::string bytes(70000, '\0');
        for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = char(i * 131 % 251);
        CHECK(prism::io::read_regular_file(folder.write("bytes.bin", bytes)) == bytes);
        CHECK(prism::io::read_regular_file(folder.write("empty.bin", "")).empty());
        // A link to a regular file is that file.
        std::filesystem::create_symlink(folder.path() / "bytes.bin", folder.path() / "link.bin");
        CHECK(prism::io::read_regular_file(folder.path() / "link.bin") == bytes);
    }
    SUBCASE("absent, a folder") {
        refused(folder.path() / "absent.png", "image file", "no such image file");
        refused(folder.path(), "image file", "is a directory, not a file");
    }
    SUBCASE("larger than prism reads, refused before it is read (a sparse file)") {
        const std::filesystem::path huge = folder.write("huge.png", "");
        std::filesystem::resize_file(huge, prism::io::max_file_bytes + 1);
        refused(huge, "image file", "the image file is 2048 MiB; prism reads at most 2048 MiB");
        std::filesystem::resize_file(huge, 3 * prism::io::max_file_bytes);
        refused(huge, "image file", "the image file is 6144 MiB; prism reads at most 2048 MiB");
    }
    SUBCASE("a scene file larger than prism reads as a scene, refused before it is read") {
        for (const char* name : {"huge.xml", "huge.json"}) {
            const std::filesystem::path huge = folder.write(name, "");
            std::filesystem::resize_file(huge, prism::io::max_scene_file_bytes + 1);
            const std::string message = refusal([&] { prism::io::load_scene(huge); });
            CHECK(message == huge.string() + ": the scene file is 256 MiB; prism reads at most 256 MiB");
        }
    }
    SUBCASE("a named pipe, by each reader") {
        const std::filesystem::path pipe = folder.path() / "pipe";
        REQUIRE(mkfifo(pipe.c_str(), 0600) == 0);
        refused(pipe, "scene file", "not a regular file");
        for (const char* name : {"pipe.xml", "pipe.json", "pipe.ply", "pipe.png"}) {
            std::filesystem::create_symlink(pipe, folder.path() / name);
            const std::filesystem::path path = folder.path() / name;
            const std::string expected = path.string() + ": not a regular file";
            const auto check = [&](const auto& read) {
                try {
                    read(path);
                } catch (const LoadError& error) {
                    CHECK(std::string(error.what()) == expected);
                    return;
                }
                FAIL("read " << path.string());
            };
            const std::string extension = std::filesystem::path(name).extension().string();
            if (extension == ".xml") check([](const std::filesystem::path& p) { (void)prism::io::read_xml(p); });
            if (extension == ".json") check([](const std::filesystem::path& p) { (void)prism::io::read_json(p); });
            if (extension == ".ply") check([](const std::filesystem::path& p) { (void)prism::io::read_ply(p); });
            if (extension == ".png") check([](const std::filesystem::path& p) { (void)prism::read_texels(p); });
        }
    }
    SUBCASE("a device, and a link to one") {
        if (!std::filesystem::exists("/dev/zero")) return;
        refused("/dev/zero", "binary data file", "not a regular file");
        std::filesystem::create_symlink("/dev/zero", folder.path() / "zero.xml");
        refused(folder.path() / "zero.xml", "scene file", "not a regular file");
    }
}

TEST_CASE("the fuzzers' findings stay fixed") {
    const std::filesystem::path root = std::filesystem::path(PRISM_SOURCE_DIR) / "tests/data/fuzz";
    REQUIRE(std::filesystem::is_directory(root));
    int replayed = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
        if (!entry.is_regular_file()) continue;
        std::ifstream stream(entry.path(), std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
        const std::string target = entry.path().parent_path().filename().string();
        CAPTURE(entry.path().string());
        try {
            if (target == "xml") prism::io::interpret_scene(prism::io::parse_xml(bytes, entry.path()), entry.path());
            else if (target == "json") prism::io::interpret_scene(prism::io::parse_json(bytes, entry.path()), entry.path());
            else if (target == "ply") prism::io::parse_ply(bytes, entry.path());
            // Every image found so far is broken: refused, not decoded (a Release build would
            // not notice stb writing past its table, so the refusal itself is checked).
            else if (target == "image") {
                CHECK_THROWS_AS(prism::decode_image(bytes, entry.path()), LoadError);
                CHECK_THROWS_AS(prism::decode_texels(bytes, entry.path()), LoadError);
            }
            else FAIL("unknown fuzz target folder " << target);
        } catch (const LoadError&) {
        }
        ++replayed;
    }
    CHECK(replayed >= 7);
}
