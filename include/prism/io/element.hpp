// The generic element tree both scene formats are read into: name, attributes, text and children,
// as in the XML files (the 2025 JSON files are a mechanical transliteration of them). The one
// interpreter (scene_loader.hpp) reads this tree, so XML and JSON scenes mean the same thing.
// Also the whole-file read both readers start from.
#pragma once

#include <prism/io/load_error.hpp>

#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace prism::io {

struct Element {
    std::string name;
    std::vector<std::pair<std::string, std::string>> attributes;  // in file order
    std::string text;                                             // untrimmed, as in the file
    std::vector<Element> children;                                // in file order
    // Where the element is, for messages: `<Objects>/<Mesh id="3">/<Material>`, and its line
    // (XML only; 0 when the format gives no position, as nlohmann's SAX events do not).
    std::string path;
    int line = 0;

    const std::string* attribute(std::string_view attribute_name) const {
        for (const auto& [key, value] : attributes)
            if (key == attribute_name) return &value;
        return nullptr;
    }

    // The first child of that name; the course's schemas never repeat single-valued elements.
    const Element* child(std::string_view child_name) const {
        for (const Element& c : children)
            if (c.name == child_name) return &c;
        return nullptr;
    }

    // True when the element says nothing: no attributes, no children, blank text. The files use
    // such elements (`<Textures></Textures>`, JSON `null`) to say "none".
    bool is_empty() const {
        return attributes.empty() && children.empty() &&
               std::all_of(text.begin(), text.end(), [](char c) { return is_blank(c); });
    }

    // The element's place for a LoadError: its path, and its line when known.
    std::string where() const { return line > 0 ? path + " (line " + std::to_string(line) + ")" : path; }

    static bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }
};

// `<Mesh id="3">`: the element's name, with its id when it has one, because that is how a reader
// finds the element in the file.
inline std::string element_label(std::string_view name, const std::string* id) {
    // Appended piece by piece: GCC 12 at -O3 warns -Wrestrict on `"<" + std::string(...)`
    // where nothing overlaps (GCC bug 105329), in every program that loads scenes.
    std::string label = "<";
    label.append(name);
    if (id != nullptr) {
        label += " id=\"";
        label += *id;
        label += '"';
    }
    label += '>';
    return label;
}

// Gives every element of the tree its path. The root (`<Scene>`) is named on its own and left
// out of its descendants' paths: every path of a scene file would start with it.
inline void assign_paths(Element& root) {
    const auto assign = [](auto& self, Element& element, const std::string& parent_path) -> void {
        const std::string label = element_label(element.name, element.attribute("id"));
        element.path = parent_path.empty() ? label : parent_path + "/" + label;
        for (Element& c : element.children) self(self, c, element.path);
    };
    root.path = element_label(root.name, root.attribute("id"));
    for (Element& c : root.children) assign(assign, c, "");
}

}  // namespace prism::io
