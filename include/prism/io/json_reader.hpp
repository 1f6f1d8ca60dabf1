// Reads a JSON scene file (nlohmann-json) into the generic element tree. The course's 2025 JSON
// files transliterate the XML: `_name` keys are attributes, `_data` is the text of an element
// that has attributes, an array is a repeated element, `null` an empty one, every value a string.
// The tree is built from SAX events, so a malformed file is reported inside the element being
// read (`<Objects>/<Sphere id="1">: malformed JSON: parse error at line 6, column 68: ...`).
#pragma once

#include <prism/io/element.hpp>
#include <prism/io/limits.hpp>
#include <prism/io/load_error.hpp>
#include <prism/io/read_file.hpp>

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace prism::io {

namespace detail::json {

// Builds the tree from nlohmann's SAX events. Arrays only ever repeat the element named by their
// key, so a stack of open objects, each with its last key, and array markers is all it needs.
class TreeBuilder {
public:
    using Json = nlohmann::json;

    // At most `max_nodes` elements and attributes (limits.hpp): each object and value is one.
    explicit TreeBuilder(std::uint64_t max_nodes = max_scene_nodes) : max_nodes_(max_nodes) {}

    // null is an empty element (`<TexCoordData/>`), the same as "".
    bool null() { return add_value(""); }
    bool boolean(bool value) { return add_value(value ? "true" : "false"); }
    bool number_integer(Json::number_integer_t value) { return add_value(std::to_string(value)); }
    bool number_unsigned(Json::number_unsigned_t value) { return add_value(std::to_string(value)); }
    // The number as written, so that JSON and XML scenes go through the same number parser.
    bool number_float(Json::number_float_t, const Json::string_t& written) { return add_value(written); }
    bool string(Json::string_t& value) { return add_value(std::move(value)); }
    bool binary(Json::binary_t&) { return fail("binary values have no meaning in a scene file"); }

    bool start_object(std::size_t) {
        // The unnamed document around the root is no element of the scene's.
        if (too_deep() || (!stack_.empty() && too_many())) return false;
        std::string name;
        if (!stack_.empty()) {
            const Frame& top = stack_.back();
            if (top.is_array) {
                name = top.name;
            } else {
                if (top.key.starts_with('_'))
                    return fail("attribute \"" + top.key + "\" must be a string, not an object");
                name = top.key;
            }
        }
        stack_.push_back(Frame{named(std::move(name)), false, {}, {}});
        return true;
    }

    bool key(Json::string_t& key) {
        stack_.back().key = std::move(key);
        return true;
    }

    bool end_object() {
        Frame frame = std::move(stack_.back());
        stack_.pop_back();
        if (stack_.empty()) {
            document_ = std::move(frame.element);
            return true;
        }
        parent_object().children.push_back(std::move(frame.element));
        return true;
    }

    bool start_array(std::size_t) {
        if (too_deep()) return false;
        if (stack_.empty()) return fail("the file must hold a JSON object, not an array");
        const Frame& top = stack_.back();
        if (top.is_array) return fail("an array inside an array has no meaning in a scene file");
        if (top.key.starts_with('_'))
            return fail("attribute \"" + top.key + "\" must be a string, not an array");
        stack_.push_back(Frame{Element{}, true, top.key, {}});
        return true;
    }

    bool end_array() {
        stack_.pop_back();
        return true;
    }

    bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception& error) {
        // nlohmann's message starts with "[json.exception.parse_error.101] ": an id for programs.
        std::string message = error.what();
        if (message.starts_with('[')) {
            const std::size_t end = message.find("] ");
            if (end != std::string::npos) message.erase(0, end + 2);
        }
        return fail("malformed JSON: " + message);
    }

    // The tree's root (the `Scene` element) once sax_parse has succeeded.
    Element take_root(const std::filesystem::path& file) {
        if (document_.children.size() != 1)
            throw LoadError(file, "", "the JSON object must hold exactly one key, the scene's root (\"Scene\")");
        Element root = std::move(document_.children.front());
        assign_paths(root);
        return root;
    }

    const std::string& error() const { return error_; }
    const std::string& error_path() const { return error_path_; }

private:
    struct Frame {
        Element element;   // an object being read
        bool is_array = false;
        std::string name;  // for an array: the name of the elements it repeats
        std::string key;   // for an object: the last key read
    };

    static Element named(std::string name, std::string text = {}) {
        Element element;
        element.name = std::move(name);
        element.text = std::move(text);
        return element;
    }

    Element& parent_object() {
        // Arrays never nest, so an array marker always sits right above the object holding it.
        return stack_.back().is_array ? stack_[stack_.size() - 2].element : stack_.back().element;
    }

    bool add_value(std::string value) {
        if (stack_.empty()) return fail("the file must hold a JSON object");
        if (too_many()) return false;
        Frame& top = stack_.back();
        if (top.is_array) {
            parent_object().children.push_back(named(top.name, std::move(value)));
        } else if (top.key == "_data") {
            top.element.text = std::move(value);
        } else if (top.key.starts_with('_')) {
            top.element.attributes.emplace_back(top.key.substr(1), std::move(value));
        } else {
            top.element.children.push_back(named(top.key, std::move(value)));
        }
        return true;
    }

    // The tree is labelled and destroyed by recursion, so its depth is bounded here, where the
    // parser (which keeps its own stack on the heap) opens each level. stack_ holds the unnamed
    // document as well, so it may be one deeper than the elements.
    bool too_deep() {
        if (stack_.size() <= std::size_t(max_element_depth)) return false;
        fail("elements nest more than " + std::to_string(max_element_depth) + " deep");
        // The whole path would repeat 64 labels: its two ends say where.
        const std::size_t first = error_path_.find('/'), last = error_path_.rfind('/');
        if (first != std::string::npos && first != last)
            error_path_ = error_path_.substr(0, first) + "/.../" + error_path_.substr(last + 1);
        return true;
    }

    // Elements and attributes are counted as the tree grows; nlohmann's SAX parser keeps no tree
    // of its own, so this bounds the memory the file can ask for while it is read.
    bool too_many() {
        if (++nodes_ <= max_nodes_) return false;
        fail("the file holds more than " + std::to_string(max_nodes_) +
             " elements and attributes, prism's limit (each costs some 200 bytes to read)");
        return true;
    }

    bool fail(std::string message) {
        error_ = std::move(message);
        error_path_ = current_path();
        return false;
    }

    // The path of the objects open now, with the same conventions as assign_paths.
    std::string current_path() const {
        std::vector<std::string> labels;
        for (std::size_t i = 1; i < stack_.size(); ++i)  // stack_[0] is the unnamed document
            if (!stack_[i].is_array)
                labels.push_back(element_label(stack_[i].element.name, stack_[i].element.attribute("id")));
        if (labels.size() == 1) return labels.front();
        std::string path;
        for (std::size_t i = 1; i < labels.size(); ++i) path += (i > 1 ? "/" : "") + labels[i];
        return path;
    }

    std::uint64_t max_nodes_;
    std::uint64_t nodes_ = 0;
    std::vector<Frame> stack_;
    Element document_;
    std::string error_;
    std::string error_path_;
};

}  // namespace detail::json

// Parses a scene file's contents already in memory; `path` names the file in messages.
// At most `max_nodes` elements and attributes (limits.hpp).
inline Element parse_json(std::string_view contents, const std::filesystem::path& path,
                          std::uint64_t max_nodes = max_scene_nodes) {
    detail::json::TreeBuilder builder(max_nodes);
    if (!nlohmann::json::sax_parse(contents, &builder)) throw LoadError(path, builder.error_path(), builder.error());
    return builder.take_root(path);
}

inline Element read_json(const std::filesystem::path& path) { return parse_json(read_regular_file(path, "", "scene file", max_scene_file_bytes), path); }

}  // namespace prism::io
