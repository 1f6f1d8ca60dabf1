// The <Transformations> section of a scene file (Translation, Scaling, Rotation: an angle in
// degrees and an axis, Composite: 16 numbers row by row) and the objects' references to it,
// `<Transformations>s1 t2 r1</Transformations>`, applied in the order written: `r1 t3` is first
// r1, then t3 (M = T3 R1).
#pragma once

#include <prism/io/element.hpp>
#include <prism/io/element_reader.hpp>
#include <prism/math/transform.hpp>

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace prism::io::detail::scene_loader {

class TransformationLoader {
public:
    explicit TransformationLoader(ElementReader& reader) : reader_(reader) {}

    void read(const Element& section) {
        for (const Element& element : section.children) {
            char kind = 0;
            glm::dmat4 matrix(1.0);
            if (element.name == "Translation") {
                kind = 't';
                matrix = translation(reader_.vector3(element));
            } else if (element.name == "Scaling") {
                kind = 's';
                matrix = scaling(reader_.vector3(element));
            } else if (element.name == "Rotation") {
                kind = 'r';
                const std::vector<double> v = reader_.numbers(element, 4);  // angle in degrees, then the axis
                const glm::dvec3 axis{v[1], v[2], v[3]};
                if (glm::length(axis) == 0.0) reader_.fail(element, "the rotation axis is zero");
                matrix = rotation(v[0], axis);
            } else if (element.name == "Composite") {
                kind = 'c';
                const std::vector<double> v = reader_.numbers(element, 16);
                std::array<double, 16> rows{};
                std::copy(v.begin(), v.end(), rows.begin());
                matrix = composite_from_row_major(rows);
            } else {
                reader_.note_unsupported(element);
                continue;
            }
            const std::string key = kind + reader_.required_id(element);
            if (!transformations_.emplace(key, matrix).second)
                reader_.fail(element, "a <" + element.name + "> with this id is already defined");
        }
    }

    // `<Transformations>s1 t2 r1</Transformations>`: applied in the order written.
    glm::dmat4 transformation_of(const Element& object) const {
        glm::dmat4 matrix(1.0);
        const Element* references = object.child("Transformations");
        if (references == nullptr) return matrix;
        for (std::string_view word : split_words(references->text)) {
            const char kind = word.front();
            if (kind != 't' && kind != 's' && kind != 'r' && kind != 'c')
                reader_.fail(*references, "unknown transformation kind '" + std::string(1, kind) + "' in " +
                                              in_quotes(word) + " (expected t, s, r or c followed by an id)");
            const auto found = transformations_.find(std::string(word));
            if (found == transformations_.end()) {
                const char* kinds[] = {"Translation", "Scaling", "Rotation", "Composite"};
                const char* kind_name = kinds[kind == 't' ? 0 : kind == 's' ? 1 : kind == 'r' ? 2 : 3];
                reader_.fail(*references, "unknown transformation " + in_quotes(word) + ": no <" + kind_name + " id=" +
                                              in_quotes(word.substr(1)) + ">");
            }
            matrix = found->second * matrix;
        }
        return matrix;
    }

private:
    ElementReader& reader_;
    std::map<std::string, glm::dmat4> transformations_;  // key: kind letter and id, as referenced ("t1")
};

}  // namespace prism::io::detail::scene_loader
