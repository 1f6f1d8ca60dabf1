// The one way prism reads a file its input names (a scene, a PLY, binary data, an image): whole,
// into memory, and only if it is a regular file. A scene can name anything, so the check comes
// before the file is opened: opening a named pipe for reading waits for a writer (for ever, in a
// batch job), and a device such as /dev/zero reads without end, so a reader that read "until
// the end" grew without bound. A regular file's size is known before it is read, so its bytes
// are read in one call into one buffer of that size, not grown and copied as they come.
#pragma once

#include <prism/io/limits.hpp>
#include <prism/io/load_error.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <system_error>

namespace prism::io {

// The bytes of `path`; `element` is the scene element that named it (empty for a file named on
// its own), `kind` what the messages call it ("image file": "no such image file"). Throws
// LoadError naming the file, the element and what is wrong: absent, a folder, not a regular
// file (a device, a pipe, a socket), larger than `max_bytes` (limits.hpp: max_file_bytes, or
// max_scene_file_bytes for a scene file's text), unreadable, or shorter than its size when read.
inline std::string read_regular_file(const std::filesystem::path& path, const std::string& element = "",
                                     std::string_view kind = "file", std::uint64_t max_bytes = max_file_bytes) {
    std::error_code error;
    const std::filesystem::file_status status = std::filesystem::status(path, error);
    if (status.type() == std::filesystem::file_type::not_found) throw LoadError(path, element, "no such " + std::string(kind));
    if (status.type() == std::filesystem::file_type::directory) throw LoadError(path, element, "is a directory, not a file");
    if (error) throw LoadError(path, element, "cannot open the " + std::string(kind) + ": " + error.message());
    if (status.type() != std::filesystem::file_type::regular) throw LoadError(path, element, "not a regular file");
    std::ifstream stream(path, std::ios::binary);
    if (!stream) throw LoadError(path, element, "cannot open the " + std::string(kind));
    stream.seekg(0, std::ios::end);
    const std::streamoff size = stream.tellg();
    stream.seekg(0, std::ios::beg);
    if (size < 0 || !stream) throw LoadError(path, element, "cannot read the " + std::string(kind));
    if (std::uint64_t(size) > max_bytes)
        throw LoadError(path, element,
                        "the " + std::string(kind) + " is " + std::to_string(std::uint64_t(size) >> 20) +
                            " MiB; prism reads at most " + std::to_string(max_bytes >> 20) + " MiB");
    std::string bytes(static_cast<std::size_t>(size), '\0');
    if (!stream.read(bytes.data(), size)) throw LoadError(path, element, "cannot read the " + std::string(kind));
    return bytes;
}

}  // namespace prism::io
