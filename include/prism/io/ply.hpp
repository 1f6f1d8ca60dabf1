// PLY reader (ASCII, binary little and big endian, version 1.0): positions, normals, texture
// coordinates and faces (polygons fanned into triangles); every other property and element is skipped.
#pragma once

#include <prism/io/load_error.hpp>
#include <prism/io/read_file.hpp>

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace prism::io {

struct PlyMesh {
    std::vector<glm::dvec3> positions;
    std::vector<glm::dvec3> normals;  // empty, or one per vertex
    std::vector<glm::dvec2> uvs;      // empty, or one per vertex
    std::vector<std::array<std::uint32_t, 3>> triangles;  // quads and polygons fanned
};

namespace detail::ply {

enum class Format { ascii, binary_little_endian, binary_big_endian };

enum class ScalarType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

inline std::optional<ScalarType> parse_scalar_type(std::string_view name) {
    if (name == "char" || name == "int8") return ScalarType::int8;
    if (name == "uchar" || name == "uint8") return ScalarType::uint8;
    if (name == "short" || name == "int16") return ScalarType::int16;
    if (name == "ushort" || name == "uint16") return ScalarType::uint16;
    if (name == "int" || name == "int32") return ScalarType::int32;
    if (name == "uint" || name == "uint32") return ScalarType::uint32;
    if (name == "float" || name == "float32") return ScalarType::float32;
    if (name == "double" || name == "float64") return ScalarType::float64;
    return std::nullopt;
}

inline std::size_t scalar_size(ScalarType type) {
    switch (type) {
        case ScalarType::int8:
        case ScalarType::uint8: return 1;
        case ScalarType::int16:
        case ScalarType::uint16: return 2;
        case ScalarType::int32:
        case ScalarType::uint32:
        case ScalarType::float32: return 4;
        case ScalarType::float64: return 8;
    }
    return 0;
}

inline bool is_integer(ScalarType type) {
    return type != ScalarType::float32 && type != ScalarType::float64;
}

struct Property {
    std::string name;
    ScalarType type = ScalarType::float32;  // of the items, for a list
    bool is_list = false;
    ScalarType count_type = ScalarType::uint8;
    std::size_t header_line = 0;
};

struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::vector<Property> properties;
    std::size_t header_line = 0;

    std::optional<std::size_t> find(std::string_view property_name) const {
        for (std::size_t i = 0; i < properties.size(); ++i)
            if (properties[i].name == property_name) return i;
        return std::nullopt;
    }
};

struct Header {
    Format format = Format::ascii;
    std::vector<Element> elements;
    std::size_t data_offset = 0;  // first byte after the end_header line
    std::size_t line_count = 0;   // lines of the header, for ASCII line numbers in messages
};

// Thrown by the cursors, which know neither the file nor the record; the element loop turns it
// into a LoadError naming both.
struct DataError {
    std::string message;
};

inline std::vector<std::string_view> split_words(std::string_view line) {
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
        if (i > start) words.push_back(line.substr(start, i - start));
    }
    return words;
}

inline std::optional<std::uint64_t> parse_count(std::string_view word) {
    std::uint64_t value = 0;
    const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
    if (error != std::errc() || end != word.data() + word.size()) return std::nullopt;
    return value;
}

inline Header parse_header(const std::filesystem::path& path, std::string_view data) {
    auto fail = [&](std::size_t line, const std::string& message) -> LoadError {
        return LoadError(path, "header line " + std::to_string(line), message);
    };
    Header header;
    bool has_format = false;
    std::size_t position = 0;
    for (std::size_t line_number = 1;; ++line_number) {
        const std::size_t newline = data.find('\n', position);
        if (newline == std::string_view::npos) {
            if (line_number == 1) throw fail(1, "not a PLY file (no 'ply' magic line)");
            throw fail(line_number, "header has no end_header line");
        }
        std::string_view line = data.substr(position, newline - position);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        position = newline + 1;

        if (line_number == 1) {
            if (line.find_first_not_of(" \t", 3) != std::string_view::npos || !line.starts_with("ply"))
                throw fail(1, "not a PLY file (no 'ply' magic line)");
            continue;
        }
        // Binary data before any end_header: say so rather than quote the bytes as a keyword.
        if (std::any_of(line.begin(), line.end(), [](char c) {
                const auto byte = static_cast<unsigned char>(c);
                return (byte < 0x20 && c != '\t') || byte >= 0x7f;
            }))
            throw fail(line_number, "header has no end_header line before binary data");
        const std::vector<std::string_view> words = split_words(line);
        if (words.empty()) continue;
        const std::string_view keyword = words[0];
        if (keyword == "comment" || keyword == "obj_info") continue;
        if (keyword == "end_header") {
            if (!has_format) throw fail(line_number, "header has no format line");
            header.data_offset = position;
            header.line_count = line_number;
            return header;
        }
        if (keyword == "format") {
            if (words.size() != 3) throw fail(line_number, "expected 'format <type> 1.0'");
            if (has_format) throw fail(line_number, "second format line");
            if (words[1] == "ascii") header.format = Format::ascii;
            else if (words[1] == "binary_little_endian") header.format = Format::binary_little_endian;
            else if (words[1] == "binary_big_endian") header.format = Format::binary_big_endian;
            else throw fail(line_number, "unknown format '" + std::string(words[1]) + "'");
            if (words[2] != "1.0" && words[2] != "1")
                throw fail(line_number, "unsupported PLY version '" + std::string(words[2]) + "'");
            has_format = true;
        } else if (keyword == "element") {
            if (words.size() != 3) throw fail(line_number, "expected 'element <name> <count>'");
            const std::optional<std::uint64_t> count = parse_count(words[2]);
            if (!count) throw fail(line_number, "element count '" + std::string(words[2]) + "' is not a non-negative integer");
            for (const Element& element : header.elements)
                if (element.name == words[1]) throw fail(line_number, "second element '" + element.name + "'");
            header.elements.push_back(Element{std::string(words[1]), *count, {}, line_number});
        } else if (keyword == "property") {
            if (header.elements.empty()) throw fail(line_number, "property before any element");
            Property property;
            property.header_line = line_number;
            auto scalar_type = [&](std::string_view name) {
                const std::optional<ScalarType> type = parse_scalar_type(name);
                if (!type) throw fail(line_number, "unknown property type '" + std::string(name) + "'");
                return *type;
            };
            if (words.size() >= 2 && words[1] == "list") {
                if (words.size() != 5) throw fail(line_number, "expected 'property list <count type> <item type> <name>'");
                property.is_list = true;
                property.count_type = scalar_type(words[2]);
                property.type = scalar_type(words[3]);
                property.name = std::string(words[4]);
                if (!is_integer(property.count_type))
                    throw fail(line_number, "list count type of '" + property.name + "' must be an integer type");
            } else {
                if (words.size() != 3) throw fail(line_number, "expected 'property <type> <name>'");
                property.type = scalar_type(words[1]);
                property.name = std::string(words[2]);
            }
            header.elements.back().properties.push_back(std::move(property));
        } else {
            throw fail(line_number, "unknown header keyword '" + std::string(keyword) + "'");
        }
    }
}

inline bool is_space(char c) {
    return c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == '\v' || c == '\f';
}

// ASCII data: records are read as whitespace-separated words without regard to line breaks, as
// most readers do; line numbers are kept only for the messages.
class AsciiCursor {
public:
    AsciiCursor(std::string_view data, std::size_t first_line)
        : position_(data.data()), end_(data.data() + data.size()), line_(first_line) {}

    std::size_t remaining() const { return static_cast<std::size_t>(end_ - position_); }

    double read_real(ScalarType) {
        std::string_view word = next_word();
        if (word.size() > 1 && word[0] == '+') word.remove_prefix(1);  // from_chars refuses '+'
        double value = 0.0;
        const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
        if (error == std::errc::result_out_of_range)
            throw DataError{"'" + std::string(word) + "' is out of range" + where()};
        if (error != std::errc() || end != word.data() + word.size())
            throw DataError{"'" + std::string(word) + "' is not a number" + where()};
        return value;
    }

    std::int64_t read_integer(ScalarType) {
        std::string_view word = next_word();
        if (word.size() > 1 && word[0] == '+') word.remove_prefix(1);
        std::int64_t value = 0;
        const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
        if (error != std::errc() || end != word.data() + word.size())
            throw DataError{"'" + std::string(word) + "' is not an integer" + where()};
        return value;
    }

    void skip(ScalarType type) {
        if (is_integer(type)) read_integer(type);
        else read_real(type);
    }

    void skip_many(ScalarType type, std::uint64_t count) {
        for (std::uint64_t i = 0; i < count; ++i) skip(type);
    }

    // Each value takes at least one character and one separator.
    bool can_hold(std::uint64_t values, ScalarType) const { return values <= (remaining() + 1) / 2; }

    std::string where() const { return " (line " + std::to_string(line_) + ")"; }

private:
    std::string_view next_word() {
        while (position_ != end_ && is_space(*position_)) {
            if (*position_ == '\n') ++line_;
            ++position_;
        }
        if (position_ == end_) throw DataError{"unexpected end of file" + where()};
        const char* start = position_;
        while (position_ != end_ && !is_space(*position_)) ++position_;
        return {start, static_cast<std::size_t>(position_ - start)};
    }

    const char* position_;
    const char* end_;
    std::size_t line_;
};

template <class UInt>
UInt byte_swap(UInt value) {
    if constexpr (sizeof(UInt) == 1) return value;
    else if constexpr (sizeof(UInt) == 2) return static_cast<UInt>(__builtin_bswap16(value));
    else if constexpr (sizeof(UInt) == 4) return __builtin_bswap32(value);
    else return __builtin_bswap64(value);
}

// Binary data: SwapBytes when the file's byte order differs from the machine's.
template <bool SwapBytes>
class BinaryCursor {
public:
    // first_byte: the offset of the data in the file, for the messages.
    BinaryCursor(std::string_view data, std::size_t first_byte)
        : begin_(data.data()), position_(data.data()), end_(data.data() + data.size()), first_byte_(first_byte) {}

    std::size_t remaining() const { return static_cast<std::size_t>(end_ - position_); }

    double read_real(ScalarType type) {
        switch (type) {
            case ScalarType::int8: return load<std::int8_t>();
            case ScalarType::uint8: return load<std::uint8_t>();
            case ScalarType::int16: return load<std::int16_t>();
            case ScalarType::uint16: return load<std::uint16_t>();
            case ScalarType::int32: return load<std::int32_t>();
            case ScalarType::uint32: return load<std::uint32_t>();
            case ScalarType::float32: return load<float>();
            case ScalarType::float64: return load<double>();
        }
        return 0.0;
    }

    // Only called for integer types: the header refuses floating-point counts and indices.
    std::int64_t read_integer(ScalarType type) {
        switch (type) {
            case ScalarType::int8: return load<std::int8_t>();
            case ScalarType::uint8: return load<std::uint8_t>();
            case ScalarType::int16: return load<std::int16_t>();
            case ScalarType::uint16: return load<std::uint16_t>();
            case ScalarType::int32: return load<std::int32_t>();
            case ScalarType::uint32: return load<std::uint32_t>();
            case ScalarType::float32:
            case ScalarType::float64: break;
        }
        throw DataError{"floating-point value where an integer is required" + where()};
    }

    void skip(ScalarType type) { skip_many(type, 1); }

    void skip_many(ScalarType type, std::uint64_t count) {
        if (!can_hold(count, type)) throw DataError{"unexpected end of data" + where()};
        position_ += count * scalar_size(type);
    }

    bool can_hold(std::uint64_t values, ScalarType type) const {
        return values <= remaining() / scalar_size(type);
    }

    std::string where() const {
        return " (byte " + std::to_string(first_byte_ + static_cast<std::size_t>(position_ - begin_)) + ")";
    }

private:
    template <class T>
    T load() {
        if (remaining() < sizeof(T)) throw DataError{"unexpected end of data" + where()};
        if constexpr (std::is_floating_point_v<T>) {
            using Bits = std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>;
            return std::bit_cast<T>(load<Bits>());
        } else {
            T value;
            std::memcpy(&value, position_, sizeof(T));
            position_ += sizeof(T);
            if constexpr (SwapBytes && sizeof(T) > 1) {
                using Unsigned = std::make_unsigned_t<T>;
                value = static_cast<T>(byte_swap(static_cast<Unsigned>(value)));
            }
            return value;
        }
    }

    const char* begin_;
    const char* position_;
    const char* end_;
    std::size_t first_byte_;
};

// Where each vertex property goes; `ignored` for those the mesh does not keep.
enum class VertexSlot { x, y, z, nx, ny, nz, u, v, ignored };

struct VertexLayout {
    std::vector<VertexSlot> slots;  // one per property of the vertex element
    bool has_normals = false;
    bool has_uvs = false;
};

inline VertexLayout vertex_layout(const std::filesystem::path& path, const Element& element) {
    VertexLayout layout;
    layout.slots.assign(element.properties.size(), VertexSlot::ignored);
    auto assign = [&](std::string_view name, VertexSlot slot) {
        const std::optional<std::size_t> index = element.find(name);
        if (!index) return false;
        if (element.properties[*index].is_list)
            throw LoadError(path, "header line " + std::to_string(element.properties[*index].header_line),
                            "vertex property '" + std::string(name) + "' is a list");
        layout.slots[*index] = slot;
        return true;
    };
    constexpr std::array<std::pair<const char*, VertexSlot>, 3> coordinates{
        {{"x", VertexSlot::x}, {"y", VertexSlot::y}, {"z", VertexSlot::z}}};
    for (const auto& [name, slot] : coordinates)
        if (!assign(name, slot))
            throw LoadError(path, "element vertex", "no property '" + std::string(name) + "'");
    if (element.find("nx") && element.find("ny") && element.find("nz"))
        layout.has_normals = assign("nx", VertexSlot::nx) && assign("ny", VertexSlot::ny) &&
                             assign("nz", VertexSlot::nz);
    constexpr std::array<std::pair<const char*, const char*>, 4> uv_names{
        {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}}};
    for (const auto& [u_name, v_name] : uv_names) {
        if (element.find(u_name) && element.find(v_name)) {
            layout.has_uvs = assign(u_name, VertexSlot::u) && assign(v_name, VertexSlot::v);
            break;
        }
    }
    return layout;
}

template <class Cursor>
void skip_list(Cursor& cursor, const Property& property) {
    const std::int64_t count = cursor.read_integer(property.count_type);
    if (count < 0) throw DataError{"negative list count " + std::to_string(count) + cursor.where()};
    if (!cursor.can_hold(static_cast<std::uint64_t>(count), property.type))
        throw DataError{"list count " + std::to_string(count) + " exceeds the remaining data" + cursor.where()};
    cursor.skip_many(property.type, static_cast<std::uint64_t>(count));
}

template <glm::length_t N>
bool all_finite(const glm::vec<N, double>& vector) {
    for (glm::length_t i = 0; i < N; ++i)
        if (!std::isfinite(vector[i])) return false;
    return true;
}

template <class Cursor>
void read_vertex(Cursor& cursor, const Element& element, const VertexLayout& layout, PlyMesh& mesh) {
    std::array<double, static_cast<std::size_t>(VertexSlot::ignored)> values{};
    auto value = [&](VertexSlot slot) -> double& { return values[static_cast<std::size_t>(slot)]; };
    for (std::size_t i = 0; i < element.properties.size(); ++i) {
        const Property& property = element.properties[i];
        if (property.is_list) skip_list(cursor, property);
        else if (layout.slots[i] == VertexSlot::ignored) cursor.skip(property.type);
        else value(layout.slots[i]) = cursor.read_real(property.type);
    }
    const glm::dvec3 position(value(VertexSlot::x), value(VertexSlot::y), value(VertexSlot::z));
    if (!all_finite(position)) throw DataError{"non-finite coordinate" + cursor.where()};
    mesh.positions.push_back(position);
    if (layout.has_normals) {
        const glm::dvec3 normal(value(VertexSlot::nx), value(VertexSlot::ny), value(VertexSlot::nz));
        if (!all_finite(normal)) throw DataError{"non-finite normal" + cursor.where()};
        mesh.normals.push_back(normal);
    }
    if (layout.has_uvs) {
        const glm::dvec2 uv(value(VertexSlot::u), value(VertexSlot::v));
        if (!all_finite(uv)) throw DataError{"non-finite texture coordinate" + cursor.where()};
        mesh.uvs.push_back(uv);
    }
}

// The vertex count comes from the header, so indices are checked as they are read, whichever of
// the two elements comes first in the file.
template <class Cursor>
void read_face(Cursor& cursor, const Element& element, std::size_t index_property,
               std::uint64_t vertex_count, PlyMesh& mesh) {
    for (std::size_t i = 0; i < element.properties.size(); ++i) {
        const Property& property = element.properties[i];
        if (i != index_property) {
            if (property.is_list) skip_list(cursor, property);
            else cursor.skip(property.type);
            continue;
        }
        const std::int64_t count = cursor.read_integer(property.count_type);
        if (count < 3)
            throw DataError{"face has " + std::to_string(count) + " vertex indices, at least 3 needed" + cursor.where()};
        if (!cursor.can_hold(static_cast<std::uint64_t>(count), property.type))
            throw DataError{"list count " + std::to_string(count) + " exceeds the remaining data" + cursor.where()};
        auto next_index = [&]() {
            const std::int64_t index = cursor.read_integer(property.type);
            if (index < 0 || static_cast<std::uint64_t>(index) >= vertex_count)
                throw DataError{"vertex index " + std::to_string(index) + " out of range [0, " +
                                std::to_string(vertex_count) + ")" + cursor.where()};
            return static_cast<std::uint32_t>(index);
        };
        const std::uint32_t first = next_index();
        std::uint32_t previous = next_index();
        for (std::int64_t k = 2; k < count; ++k) {
            const std::uint32_t current = next_index();
            mesh.triangles.push_back({first, previous, current});
            previous = current;
        }
    }
}

// The smallest number of bytes one record can take, so a header cannot make the reader reserve
// memory (or loop) for records the data cannot hold.
inline std::uint64_t minimum_record_size(const Element& element, Format format) {
    std::uint64_t size = 0;
    for (const Property& property : element.properties) {
        if (format == Format::ascii) size += 2;  // a digit and a separator
        else size += scalar_size(property.is_list ? property.count_type : property.type);
    }
    return size;
}

template <class Cursor>
void read_elements(const std::filesystem::path& path, const Header& header, Cursor& cursor, PlyMesh& mesh) {
    const Element* vertex_element = nullptr;
    const Element* face_element = nullptr;
    for (const Element& element : header.elements) {
        if (element.name == "vertex") vertex_element = &element;
        if (element.name == "face") face_element = &element;
    }
    if (!vertex_element) throw LoadError(path, "header", "no vertex element");
    if (!face_element) throw LoadError(path, "header", "no face element (point clouds are not meshes)");
    const VertexLayout layout = vertex_layout(path, *vertex_element);
    if (vertex_element->count > std::uint64_t{std::numeric_limits<std::uint32_t>::max()} + 1)
        throw LoadError(path, "element vertex", std::to_string(vertex_element->count) +
                                                    " vertices cannot be indexed with 32 bits");
    std::optional<std::size_t> index_property = face_element->find("vertex_indices");
    if (!index_property) index_property = face_element->find("vertex_index");
    if (!index_property)
        throw LoadError(path, "element face", "no property 'vertex_indices' or 'vertex_index'");
    {
        const Property& indices = face_element->properties[*index_property];
        if (!indices.is_list || !is_integer(indices.type))
            throw LoadError(path, "header line " + std::to_string(indices.header_line),
                            "'" + indices.name + "' must be a list of an integer type");
    }

    for (const Element& element : header.elements) {
        if (element.properties.empty()) continue;  // its records take no bytes
        const std::uint64_t minimum_size = minimum_record_size(element, header.format);
        const std::uint64_t capacity = (cursor.remaining() + (header.format == Format::ascii ? 1 : 0)) / minimum_size;
        if (element.count > capacity)
            throw LoadError(path, "element " + element.name,
                            "header declares " + std::to_string(element.count) + " records of at least " +
                                std::to_string(minimum_size) + " bytes, but only " +
                                std::to_string(cursor.remaining()) + " bytes of data remain");
        const auto count = static_cast<std::size_t>(element.count);
        std::size_t record = 0;
        try {
            if (&element == vertex_element) {
                mesh.positions.reserve(count);
                if (layout.has_normals) mesh.normals.reserve(count);
                if (layout.has_uvs) mesh.uvs.reserve(count);
                for (; record < count; ++record) read_vertex(cursor, element, layout, mesh);
            } else if (&element == face_element) {
                mesh.triangles.reserve(count);
                for (; record < count; ++record)
                    read_face(cursor, element, *index_property, vertex_element->count, mesh);
            } else {
                for (; record < count; ++record) {
                    for (const Property& property : element.properties) {
                        if (property.is_list) skip_list(cursor, property);
                        else cursor.skip(property.type);
                    }
                }
            }
        } catch (const DataError& error) {
            throw LoadError(path, "element " + element.name + " " + std::to_string(record), error.message);
        }
    }
}

}  // namespace detail::ply

// Parses a PLY file's bytes already in memory; `path` names the file in messages.
inline PlyMesh parse_ply(std::string_view bytes, const std::filesystem::path& path) {
    using namespace detail::ply;
    const Header header = parse_header(path, bytes);
    const std::string_view data = bytes.substr(header.data_offset);
    PlyMesh mesh;
    constexpr bool little_endian_machine = std::endian::native == std::endian::little;
    if (header.format == Format::ascii) {
        AsciiCursor cursor(data, header.line_count + 1);
        read_elements(path, header, cursor, mesh);
    } else if ((header.format == Format::binary_little_endian) == little_endian_machine) {
        BinaryCursor<false> cursor(data, header.data_offset);
        read_elements(path, header, cursor, mesh);
    } else {
        BinaryCursor<true> cursor(data, header.data_offset);
        read_elements(path, header, cursor, mesh);
    }
    return mesh;
}

inline PlyMesh read_ply(const std::filesystem::path& path) { return parse_ply(read_regular_file(path), path); }

}  // namespace prism::io
