// The course's binary data files (`binaryFile="..."` on VertexData, TexCoordData and Faces): a
// little-endian int32 record count, then that many records of `width` values, float32 for
// vertex positions and texture coordinates, int32 for face indices. A count that the file's
// size cannot hold is an error, never a huge allocation.
#pragma once

#include <prism/io/load_error.hpp>
#include <prism/io/read_file.hpp>

#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace prism::io {

namespace detail {

template <class Value>
std::vector<Value> read_binary_records(const std::filesystem::path& path, int width, const std::string& element) {
    static_assert(std::endian::native == std::endian::little, "binary data files are little-endian");
    const std::string bytes = read_regular_file(path, element, "binary data file");
    std::int32_t count = 0;
    if (bytes.size() < sizeof count) throw LoadError(path, element, "too short for its record count");
    std::memcpy(&count, bytes.data(), sizeof count);
    if (count < 0) throw LoadError(path, element, "negative record count " + std::to_string(count));
    const std::size_t needed = std::size_t(count) * std::size_t(width) * sizeof(Value);
    if (bytes.size() - sizeof count < needed)
        throw LoadError(path, element,
                        "declares " + std::to_string(count) + " records of " + std::to_string(width) +
                            " values but holds " + std::to_string((bytes.size() - sizeof count) / sizeof(Value)) +
                            " values");
    std::vector<Value> values(std::size_t(count) * std::size_t(width));
    if (!values.empty()) std::memcpy(values.data(), bytes.data() + sizeof count, needed);
    return values;
}

}  // namespace detail

// `width` floats per record, widened to double (the scene description's precision).
inline std::vector<double> read_binary_floats(const std::filesystem::path& path, int width, const std::string& element) {
    const std::vector<float> values = detail::read_binary_records<float>(path, width, element);
    return {values.begin(), values.end()};
}

inline std::vector<long long> read_binary_integers(const std::filesystem::path& path, int width,
                                                   const std::string& element) {
    const std::vector<std::int32_t> values = detail::read_binary_records<std::int32_t>(path, width, element);
    return {values.begin(), values.end()};
}

}  // namespace prism::io
