// Reads an XML scene file (pugixml) into the generic element tree, keeping each element's line
// for messages. A malformed file is reported with pugixml's description, its line and column, and
// the elements open at the fault, e.g. `<Objects>/<Mesh id="1"> (line 31, column 9)`.
#pragma once

#include <prism/io/element.hpp>
#include <prism/io/limits.hpp>
#include <prism/io/load_error.hpp>
#include <prism/io/read_file.hpp>

#include <pugixml.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace prism::io {

namespace detail::xml {

// Maps byte offsets to 1-based line numbers; pugixml only knows offsets. The elements are asked
// for in document order, so the count of newlines goes forward from the last offset asked (an
// earlier one, for a message, counts from the start): no table of line starts, which a file of
// newlines would have made eight times its size.
class LineTable {
public:
    explicit LineTable(std::string_view text) : text_(text) {}
    int line(std::ptrdiff_t offset) {
        if (offset < 0) return 0;
        const std::size_t to = std::min(std::size_t(offset), text_.size());
        if (to < counted_) counted_ = 0, line_ = 1;
        line_ += std::count(text_.begin() + std::ptrdiff_t(counted_), text_.begin() + std::ptrdiff_t(to), '\n');
        counted_ = to;
        return int(line_);
    }
    int column(std::ptrdiff_t offset) const {
        if (offset < 0) return 0;
        const std::size_t to = std::min(std::size_t(offset), text_.size());
        const std::size_t newline = to == 0 ? std::string_view::npos : text_.rfind('\n', to - 1);
        return int(to - (newline == std::string_view::npos ? 0 : newline + 1)) + 1;
    }

private:
    std::string_view text_;
    std::size_t counted_ = 0;  // newlines are counted up to here
    std::ptrdiff_t line_ = 1;  // the line of offset counted_
};

// The id attribute's value inside a start tag's text (`Mesh id="3" shadingMode="smooth"`).
inline const std::string* find_id(std::string_view tag, std::string& storage) {
    for (std::size_t at = tag.find("id"); at != std::string_view::npos; at = tag.find("id", at + 2)) {
        if (at == 0 || !Element::is_blank(tag[at - 1])) continue;
        std::size_t i = at + 2;
        while (i < tag.size() && Element::is_blank(tag[i])) ++i;
        if (i >= tag.size() || tag[i] != '=') continue;
        ++i;
        while (i < tag.size() && Element::is_blank(tag[i])) ++i;
        if (i >= tag.size() || (tag[i] != '"' && tag[i] != '\'')) continue;
        const std::size_t end = tag.find(tag[i], i + 1);
        if (end == std::string_view::npos) return nullptr;
        storage = std::string(tag.substr(i + 1, end - i - 1));
        return &storage;
    }
    return nullptr;
}

// Calls visit(start, tag, attributes) for each tag of `text` that opens before `offset`, in
// order: `start` is the offset of its '<', `tag` what lies between '<' and '>', `attributes` the
// count of '=' outside quotes in it. Comments, CDATA sections, processing instructions and the
// DOCTYPE are skipped. Stops where visit returns false, at `offset`, or at a tag that does not
// close (where a malformed file goes wrong). A small scanner of its own, since pugixml reports
// neither inside which element a fault lies nor how many nodes it is about to build.
template <class Visit>
void scan_tags(std::string_view text, std::size_t offset, Visit visit) {
    std::size_t i = 0;
    const auto skip_past = [&](std::size_t from, std::string_view terminator) {
        const std::size_t end = text.find(terminator, from);
        return end == std::string_view::npos ? text.size() : end + terminator.size();
    };
    while (i < offset) {
        const std::size_t start = text.find('<', i);
        if (start == std::string_view::npos || start >= offset) return;
        const std::string_view rest = text.substr(start);
        if (rest.starts_with("<!--")) { i = skip_past(start + 4, "-->"); continue; }
        if (rest.starts_with("<![CDATA[")) { i = skip_past(start + 9, "]]>"); continue; }
        if (rest.starts_with("<?")) { i = skip_past(start + 2, "?>"); continue; }
        if (rest.starts_with("<!")) { i = skip_past(start + 2, ">"); continue; }
        std::size_t end = start + 1, attributes = 0;
        char quote = 0;
        for (; end < text.size(); ++end) {
            const char c = text[end];
            if (quote != 0) {
                if (c == quote) quote = 0;
            } else if (c == '"' || c == '\'') {
                quote = c;
            } else if (c == '=') {
                ++attributes;
            } else if (c == '>' || c == '<') {
                break;
            }
        }
        if (end >= text.size() || text[end] != '>' || end >= offset) return;
        if (!visit(start, text.substr(start + 1, end - start - 1), attributes)) return;
        i = end + 1;
    }
}

// The path of the elements still open at `offset`: what a user needs to find a fault.
inline std::string open_elements_at(std::string_view text, std::size_t offset) {
    std::vector<std::string> open;
    // A tag that does not close before the fault is where the fault is: its parents are open.
    scan_tags(text, offset, [&](std::size_t, std::string_view tag, std::size_t) {
        if (tag.starts_with('/')) {
            if (!open.empty()) open.pop_back();
        } else if (!tag.ends_with('/')) {
            std::size_t name_end = 0;
            while (name_end < tag.size() && !Element::is_blank(tag[name_end]) && tag[name_end] != '/') ++name_end;
            std::string id;
            open.push_back(element_label(tag.substr(0, name_end), find_id(tag, id)));
        }
        return true;
    });
    // Paths leave the root out (see assign_paths), unless it is all there is.
    if (open.size() == 1) return open.front();
    std::string path;
    for (std::size_t k = 1; k < open.size(); ++k) path += (k > 1 ? "/" : "") + open[k];
    return path;
}

// The offset of the start tag at which the file's elements and attributes pass `limit`, or
// npos if they do not. Counted before pugixml builds its tree, which would cost the memory the
// limit is there to bound.
inline std::size_t where_nodes_pass(std::string_view text, std::uint64_t limit) {
    std::uint64_t nodes = 0;
    std::size_t passed = std::string_view::npos;
    scan_tags(text, text.size(), [&](std::size_t start, std::string_view tag, std::size_t attributes) {
        if (tag.starts_with('/')) return true;
        nodes += 1 + attributes;
        if (nodes <= limit) return true;
        passed = start;
        return false;
    });
    return passed;
}

// Recursive, so the depth is checked first: the file must not choose how deep the stack goes.
inline Element convert(const pugi::xml_node& node, LineTable& lines, const std::filesystem::path& path,
                       int depth = 1) {
    Element element;
    element.name = node.name();
    element.line = lines.line(node.offset_debug());
    if (depth > max_element_depth)
        throw LoadError(path, element_label(element.name, nullptr) + " (line " + std::to_string(element.line) + ")",
                        "elements nest more than " + std::to_string(max_element_depth) + " deep");
    for (const pugi::xml_attribute& attribute : node.attributes())
        element.attributes.emplace_back(attribute.name(), attribute.value());
    for (const pugi::xml_node& child : node.children()) {
        if (child.type() == pugi::node_element) {
            element.children.push_back(convert(child, lines, path, depth + 1));
        } else if (child.type() == pugi::node_pcdata || child.type() == pugi::node_cdata) {
            // Text split by a comment (`1 2 <!-- -->3`) must not glue two numbers together.
            if (!element.text.empty()) element.text += ' ';
            element.text += child.value();
        }
    }
    return element;
}

}  // namespace detail::xml

// Parses a scene file's contents already in memory; `path` names the file in messages.
// At most `max_nodes` elements and attributes (limits.hpp).
inline Element parse_xml(std::string_view contents, const std::filesystem::path& path,
                         std::uint64_t max_nodes = max_scene_nodes) {
    detail::xml::LineTable lines(contents);
    if (const std::size_t passed = detail::xml::where_nodes_pass(contents, max_nodes); passed != std::string_view::npos) {
        std::string where = detail::xml::open_elements_at(contents, passed + 1);
        where += (where.empty() ? "(line " : " (line ") + std::to_string(lines.line(std::ptrdiff_t(passed))) + ")";
        throw LoadError(path, where,
                        "the file holds more than " + std::to_string(max_nodes) +
                            " elements and attributes, prism's limit (each costs some 200 bytes to read)");
    }
    pugi::xml_document document;
    const pugi::xml_parse_result result = document.load_buffer(contents.data(), contents.size());
    if (!result) {
        std::string where = detail::xml::open_elements_at(contents, std::size_t(result.offset));
        where += (where.empty() ? "(line " : " (line ") + std::to_string(lines.line(result.offset)) +
                 ", column " + std::to_string(lines.column(result.offset)) + ")";
        throw LoadError(path, where, std::string("malformed XML: ") + result.description());
    }
    const pugi::xml_node root = document.document_element();
    if (!root) throw LoadError(path, "", "the file holds no XML element");
    Element tree = detail::xml::convert(root, lines, path);
    assign_paths(tree);
    return tree;
}

inline Element read_xml(const std::filesystem::path& path) { return parse_xml(read_regular_file(path, "", "scene file", max_scene_file_bytes), path); }

}  // namespace prism::io
