// The <Textures> section of a scene file, in both of the course's schemas, into Scene::images and
// Scene::textures, and the objects' references to them:
//   - 2020+: <Images><Image id>path</Image></Images> and <TextureMap id type="image|perlin|
//     checkerboard"> (ImageId, DecalMode, Interpolation, Normalizer, BumpFactor, NoiseConversion,
//     NoiseScale, NumOctaves, Scale, Offset, BlackColor, WhiteColor, degamma="true"); objects name
//     them by <Textures>1 2</Textures>.
//   - 2017-2019: <Texture id bumpmap bumpmapMultiplier> with <ImageName>path|perlin|checkerboard
//     </ImageName> (ScalingFactor: Perlin's noise scale or the checkerboard's scale; Appearance
//     patch -> absval, vein -> linear); objects name them by <Texture>1</Texture>.
// bumpmap="true" adds a bump: the 2019 renderer that ships these scenes (EgeCiklabakkal/Raytracer)
// applies the DecalMode's colour AND bumps the normal with the same texture, and the 2022 remake of
// its scenes writes the pair explicitly (sphere_bump_nobump.xml's bumped sphere: texture 2,
// bumpmap="true" + replace_kd; sphere_nobump_bump.xml: <Textures>1 2</Textures>, replace_kd +
// bump_normal). So such a texture becomes two scene textures, the DecalMode one and a bump_normal
// one with BumpFactor = bumpmapMultiplier (default 1), and an object naming it gets both, in that
// order. With DecalMode bump_normal or no DecalMode, bumpmap="true" gives the bump texture alone.
// Images are decoded once per file (decode_texels: 8-bit files keep their bytes 0..255), relative to the scene's
// folder, each weighed from its header first against the memory the scene may take with its meshes
// (MemoryUse, limits.hpp). The replace_background texture, named by no object in the course's files
// (galactica_static.xml), is the scene's background; a scene may have one.
#pragma once

#include <prism/image/image_io.hpp>
#include <prism/io/element.hpp>
#include <prism/io/element_reader.hpp>
#include <prism/io/limits.hpp>
#include <prism/io/load_error.hpp>
#include <prism/io/read_file.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <cstddef>
#include <exception>
#include <initializer_list>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

namespace prism::io::detail::scene_loader {

class TextureLoader {
public:
    TextureLoader(ElementReader& reader, scene::Scene& scene, const ResourceLimits& limits, MemoryUse& memory)
        : reader_(reader), scene_(scene), limits_(limits), memory_(memory) {}

    // One <Textures> section.
    void read(const Element& section) {
        for (const Element& element : section.children) {
            if (element.name == "Images") {
                decode_side_by_side(element);
                for (const Element& image : element.children) {
                    if (image.name != "Image") {
                        reader_.note_unsupported(image);
                        continue;
                    }
                    if (!image_ids_.emplace(reader_.required_id(image), decode(image, reader_.text_of(image))).second)
                        reader_.fail(image, "an <Image> with this id is already defined");
                }
            } else if (element.name == "TextureMap") {
                add(element, {read_texture_map(element)});
                note_unread(element, {"ImageId", "BumpFactor", "NoiseConversion", "NoiseScale",
                                                       "NumOctaves", "Scale"});
            } else if (element.name == "Texture") {
                add(element, read_legacy_texture(element));
                note_unread(element, {"ImageName", "ScalingFactor", "Appearance"});
            } else {
                reader_.note_unsupported(element);
            }
        }
    }

    // The textures an object names, in the order written: <Textures>1 2</Textures> (2020+) or
    // <Texture>1</Texture> (2017-2019); empty when it names none.
    std::vector<std::size_t> textures_of(const Element& object) const {
        std::vector<std::size_t> indices;
        for (const Element& reference : object.children) {
            if (reference.name != "Textures" && reference.name != "Texture") continue;
            for (std::string_view id : split_words(reference.text)) {
                const auto found = texture_ids_.find(std::string(id));
                if (found == texture_ids_.end()) reader_.fail(reference, "unknown texture id " + in_quotes(id));
                indices.insert(indices.end(), found->second.begin(), found->second.end());
                if (indices.size() > max_textures_per_object)
                    reader_.fail(reference, "more than " + std::to_string(max_textures_per_object) +
                                                " textures for one object, prism's limit (each is applied at every "
                                                "shading point)");
            }
        }
        return indices;
    }

    // <ImageId>: an <Image> of <Textures><Images>.
    std::size_t image_of(const Element& reference) const {
        const std::string id = reader_.text_of(reference);
        const auto found = image_ids_.find(id);
        if (found == image_ids_.end())
            reader_.fail(reference, "unknown image id " + in_quotes(id) + ": no <Image> of <Textures><Images> has it");
        return found->second;
    }

private:
    // Names the children read neither by read_common (nor DecalMode) nor by the schema's own code.
    void note_unread(const Element& element, std::initializer_list<std::string_view> schema_children) {
        for (const Element& child : element.children) {
            const bool common = child.name == "DecalMode" || child.name == "Interpolation" ||
                                child.name == "Normalizer" || child.name == "BlackColor" ||
                                child.name == "WhiteColor" || child.name == "Offset";
            if (!common && std::find(schema_children.begin(), schema_children.end(), child.name) == schema_children.end())
                reader_.note_unsupported(child);
        }
    }

    scene::DecalMode decal_mode_of(const Element& element) const {
        using enum scene::DecalMode;
        return reader_.keyword<scene::DecalMode>(element, "decal mode",
                                                 {{"replace_kd", replace_kd},
                                                  {"blend_kd", blend_kd},
                                                  {"replace_ks", replace_ks},
                                                  {"replace_background", replace_background},
                                                  {"replace_normal", replace_normal},
                                                  {"bump_normal", bump_normal},
                                                  {"replace_all", replace_all}});
    }

    // The children whose meaning is the same in both schemas; DecalMode is left to the caller,
    // since the older schema combines it with bumpmap.
    void read_common(const Element& element, scene::Texture& texture) const {
        texture.id = reader_.required_id(element);
        texture.degamma = reader_.boolean_attribute(element, "degamma", false);
        if (const Element* e = element.child("Interpolation")) {
            using enum scene::Interpolation;
            texture.interpolation = reader_.keyword<scene::Interpolation>(
                *e, "interpolation", {{"nearest", nearest}, {"bilinear", bilinear}, {"trilinear", trilinear}});
        }
        if (const Element* e = element.child("Normalizer")) texture.normalizer = reader_.positive(*e);
        if (const Element* e = element.child("Offset")) texture.offset = reader_.number(*e);
        if (const Element* e = element.child("BlackColor")) texture.black_color = reader_.vector3(*e);
        if (const Element* e = element.child("WhiteColor")) texture.white_color = reader_.vector3(*e);
    }

    scene::Texture read_texture_map(const Element& element) {
        scene::Texture texture;
        read_common(element, texture);
        {
            using enum scene::TextureKind;
            texture.kind = reader_.keyword<scene::TextureKind>(element, "texture type",
                                                               reader_.required_attribute(element, "type"),
                                                               {{"image", image}, {"perlin", perlin}, {"checkerboard", checkerboard}});
        }
        if (texture.kind == scene::TextureKind::image) texture.image = image_of(reader_.required(element, "ImageId"));
        if (const Element* e = element.child("DecalMode")) texture.decal_mode = decal_mode_of(*e);
        if (const Element* e = element.child("BumpFactor")) texture.bump_factor = reader_.number(*e);
        if (const Element* e = element.child("NoiseConversion")) {
            using enum scene::NoiseConversion;
            texture.noise_conversion =
                reader_.keyword<scene::NoiseConversion>(*e, "noise conversion", {{"absval", absval}, {"linear", linear}});
        }
        if (const Element* e = element.child("NoiseScale")) texture.noise_scale = reader_.positive(*e);
        if (const Element* e = element.child("NumOctaves")) texture.num_octaves = int(reader_.integer_within_limit(*e, 1, max_noise_octaves));
        if (const Element* e = element.child("Scale")) texture.scale = reader_.positive(*e);
        return texture;
    }

    // One or two scene textures: see the header's comment on bumpmap.
    std::vector<scene::Texture> read_legacy_texture(const Element& element) {
        scene::Texture texture;
        read_common(element, texture);
        const Element& image_name = reader_.required(element, "ImageName");
        const std::string name = reader_.text_of(image_name);
        const Element* scaling = element.child("ScalingFactor");
        if (name == "perlin") {
            texture.kind = scene::TextureKind::perlin;
            if (scaling != nullptr) texture.noise_scale = reader_.positive(*scaling);
            if (const Element* e = element.child("Appearance")) {
                using enum scene::NoiseConversion;
                texture.noise_conversion =
                    reader_.keyword<scene::NoiseConversion>(*e, "Perlin appearance", {{"patch", absval}, {"vein", linear}});
            }
        } else if (name == "checkerboard") {
            texture.kind = scene::TextureKind::checkerboard;
            if (scaling != nullptr) texture.scale = reader_.positive(*scaling);
        } else {
            texture.kind = scene::TextureKind::image;
            texture.image = decode(image_name, name);
        }

        const bool bumpmap = reader_.boolean_attribute(element, "bumpmap", false);
        if (const std::string* multiplier = element.attribute("bumpmapMultiplier"))
            texture.bump_factor = reader_.parse_number(element, trim(*multiplier));
        const Element* decal = element.child("DecalMode");
        if (decal != nullptr) texture.decal_mode = decal_mode_of(*decal);
        std::vector<scene::Texture> made;
        if (!bumpmap || (decal != nullptr && texture.decal_mode != scene::DecalMode::bump_normal))
            made.push_back(texture);
        if (bumpmap) {
            texture.decal_mode = scene::DecalMode::bump_normal;
            made.push_back(texture);
        }
        return made;
    }

    void add(const Element& element, std::vector<scene::Texture> made) {
        std::vector<std::size_t> indices;
        for (scene::Texture& texture : made) {
            if (texture.decal_mode == scene::DecalMode::replace_background) {
                if (scene_.background_texture)
                    reader_.fail(element, "a second replace_background texture: texture " +
                                              in_quotes(scene_.textures[*scene_.background_texture].id) +
                                              " is already the background");
                scene_.background_texture = scene_.textures.size();
            }
            indices.push_back(scene_.textures.size());
            scene_.textures.push_back(std::move(texture));
        }
        if (!texture_ids_.emplace(reader_.required_id(element), std::move(indices)).second)
            reader_.fail(element, "a texture with this id is already defined");
    }

    // The file an <Image> or <ImageName> names, relative to the scene's folder.
    std::filesystem::path image_path(const std::string& written) const {
        return (reader_.folder() / written).lexically_normal();
    }

    // Decodes the files of an <Images> block's <Image> elements side by side, before the block is
    // read: stb decodes a file on one thread, and VeachAjar's three JPEGs (9.9 million pixels)
    // took their decoding times one after another. decode() then takes each result, or its
    // error, in the block's order, so a scene with several faults reports the same first one.
    void decode_side_by_side(const Element& images) {
        std::vector<std::filesystem::path> paths;
        std::vector<const Element*> naming;  // the first <Image> naming each path
        for (const Element& image : images.children) {
            if (image.name != "Image") continue;
            const std::string written = reader_.text_of(image);
            if (written.empty()) continue;  // decode() reports it in turn
            const std::filesystem::path path = image_path(written);
            if (!decoded_.contains(path) && std::find(paths.begin(), paths.end(), path) == paths.end()) {
                paths.push_back(path);
                naming.push_back(&image);
            }
        }
        if (paths.size() < 2) return;  // one file: decode() reads it in turn
        // Read and weighed one after another, in the block's order, then decoded side by side. A
        // file that cannot be read or whose header is bad ends the reading: decode() meets its
        // fault before any file after it. A file past the memory limit ends the load there,
        // before anything is decoded.
        std::vector<Predecoded> results(paths.size());
        std::vector<std::string> bytes(paths.size());
        std::size_t read = 0;
        while (read < paths.size()) {
            const std::size_t i = read++;
            Measured measured;
            try {
                measured = measure(paths[i]);
            } catch (...) {
                results[i].error = std::current_exception();
                break;
            }
            try {
                charge(paths[i], measured);
            } catch (const LoadError& error) {
                throw LoadError(reader_.file(), naming[i]->where(), error.what());
            }
            bytes[i] = std::move(measured.bytes);
        }
        tbb::parallel_for(std::size_t(0), read, [&](std::size_t i) {
            if (results[i].error) return;
            try {
                results[i].texels = std::make_shared<const Texels>(decode_texels(bytes[i], paths[i]));
            } catch (...) {
                results[i].error = std::current_exception();
            }
            bytes[i] = std::string();
        });
        for (std::size_t i = 0; i < read; ++i) predecoded_.insert_or_assign(paths[i], std::move(results[i]));
    }

    // An image file's bytes and its size from its header (image_extent): what it will take is
    // known before it is decoded.
    struct Measured {
        std::string bytes;
        ImageExtent extent;
    };
    static Measured measure(const std::filesystem::path& path) {
        Measured measured{read_regular_file(path, "", "image file"), {}};
        measured.extent = image_extent(measured.bytes, path);
        return measured;
    }

    // Adds a measured image to what the scene will take (MemoryUse, limits.hpp); past the memory
    // limit, refused, naming the file.
    void charge(const std::filesystem::path& path, const Measured& image) {
        const ImageExtent& extent = image.extent;
        memory_.texture_bytes += texture_bytes(std::uint64_t(extent.width) * std::uint64_t(extent.height), extent.texel_bytes);
        if (memory_.over(limits_.memory_bytes))
            throw LoadError(path, "",
                            "the scene's textures reach " + MemoryUse::mib(memory_.texture_bytes) + " here (this one " +
                                std::to_string(extent.width) + " x " + std::to_string(extent.height) +
                                "): " + memory_.over_message(limits_.memory_bytes));
    }

    // Decodes `written` (relative to the scene's folder) once; later textures naming the same file
    // share it. A missing or undecodable file fails here, naming the element that asked for it.
    std::size_t decode(const Element& element, const std::string& written) {
        if (written.empty()) reader_.fail(element, "the image path is empty");
        const std::filesystem::path path = image_path(written);
        if (const auto found = decoded_.find(path); found != decoded_.end()) return found->second;
        scene::TextureImage image;
        image.path = path;
        try {
            if (const auto found = predecoded_.find(path); found != predecoded_.end()) {
                Predecoded predecoded = std::move(found->second);
                predecoded_.erase(found);
                if (predecoded.error) std::rethrow_exception(predecoded.error);
                image.texels = std::move(predecoded.texels);
            } else {
                const Measured measured = measure(path);
                charge(path, measured);
                image.texels = std::make_shared<const Texels>(decode_texels(measured.bytes, path));
            }
        } catch (const LoadError& error) {
            throw LoadError(reader_.file(), element.where(), error.what());
        }
        const std::string extension = prism::detail::lowercase_extension(path);
        image.high_dynamic_range = extension == ".hdr" || extension == ".exr";
        decoded_.emplace(path, scene_.images.size());
        scene_.images.push_back(std::move(image));
        return scene_.images.size() - 1;
    }

    ElementReader& reader_;
    scene::Scene& scene_;
    const ResourceLimits& limits_;
    MemoryUse& memory_;  // shared with the object and camera loaders
    std::map<std::string, std::size_t> image_ids_;
    std::map<std::string, std::vector<std::size_t>> texture_ids_;  // an older-schema bump map makes two
    std::map<std::filesystem::path, std::size_t> decoded_;
    // Files decode_side_by_side has decoded and decode() has not yet taken: the image or what
    // reading it threw.
    struct Predecoded {
        std::shared_ptr<const Texels> texels;
        std::exception_ptr error;
    };
    std::map<std::filesystem::path, Predecoded> predecoded_;
};

}  // namespace prism::io::detail::scene_loader
