// The <BRDFs> section of a scene file (CENG795 hw6), XML or JSON, and the materials' BRDF="id"
// references to it: OriginalPhong, ModifiedPhong, OriginalBlinnPhong, ModifiedBlinnPhong (with
// normalized="true|false" on the modified ones) and TorranceSparrow (kdfresnel="true|false"),
// each with an <Exponent>. An unknown model, a repeated id or a reference to no BRDF is a
// LoadError that names the element.
#pragma once

#include <prism/io/element.hpp>
#include <prism/io/element_reader.hpp>
#include <prism/io/load_error.hpp>
#include <prism/scene/scene.hpp>

#include <map>
#include <optional>
#include <string>
#include <utility>

namespace prism::io::detail::scene_loader {

class BrdfLoader {
public:
    explicit BrdfLoader(ElementReader& reader) : reader_(reader) {}

    void read(const Element& section) {
        for (const Element& element : section.children) {
            scene::Brdf brdf;
            brdf.model = reader_.keyword<scene::BrdfModel>(
                element, "BRDF", element.name,
                {{"OriginalPhong", scene::BrdfModel::original_phong},
                 {"ModifiedPhong", scene::BrdfModel::modified_phong},
                 {"OriginalBlinnPhong", scene::BrdfModel::original_blinn_phong},
                 {"ModifiedBlinnPhong", scene::BrdfModel::modified_blinn_phong},
                 {"TorranceSparrow", scene::BrdfModel::torrance_sparrow}});
            brdf.id = reader_.required_id(element);
            brdf.exponent = reader_.non_negative(reader_.required(element, "Exponent"));
            // Only the modified models have a normalised form and only Torrance-Sparrow a
            // kdfresnel; the other models ignore these attributes (material/brdf/).
            brdf.normalized = reader_.boolean_attribute(element, "normalized", false);
            brdf.kdfresnel = reader_.boolean_attribute(element, "kdfresnel", false);
            reader_.note_unsupported_children(element, {"Exponent"});
            if (!brdfs_.emplace(brdf.id, brdf).second) reader_.fail(element, "a BRDF with this id is already defined");
        }
    }

    // The BRDF a <Material BRDF="id"> names, or none without the attribute.
    std::optional<scene::Brdf> brdf_of(const Element& material) const {
        const std::string* id = material.attribute("BRDF");
        if (id == nullptr) return std::nullopt;
        const auto found = brdfs_.find(std::string(trim(*id)));
        if (found == brdfs_.end()) reader_.fail(material, "unknown BRDF id " + in_quotes(trim(*id)));
        return found->second;
    }

private:
    ElementReader& reader_;
    std::map<std::string, scene::Brdf> brdfs_;
};

}  // namespace prism::io::detail::scene_loader
