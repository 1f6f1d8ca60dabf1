// Where a scene's ImageName may be written: inside the output folder the user chose, never outside
// it. A downloaded scene file must not be able to name `/home/user/photo.png` or `../../x.png` and
// overwrite a file the user can write, so absolute names, names that climb out with `..`, and names
// that leave through a symbolic link already in the folder are refused. No option lifts this: a
// user who wants images elsewhere says so with --output-dir, not the scene file.
#pragma once

#include <prism/io/load_error.hpp>

#include <cerrno>
#include <climits>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include <unistd.h>

namespace prism::io {

// The path `image_name` (as written in the scene file `scene_file`, at `element`) resolves to under
// `output_dir`; throws a LoadError naming the file and the element when it would leave the folder.
inline std::filesystem::path confined_output_path(const std::filesystem::path& output_dir,
                                                  const std::filesystem::path& image_name,
                                                  const std::filesystem::path& scene_file, const std::string& element) {
    // A name of kilobytes is quoted by its two ends: the message stays one readable line.
    const std::string& written = image_name.native();
    const std::string quoted =
        "\"" + (written.size() <= 200 ? written : written.substr(0, 120) + "..." + written.substr(written.size() - 60)) + "\"";
    const auto refuse = [&](const std::string& why) {
        return LoadError(scene_file, element, quoted + " " + why + ": images are written inside --output-dir only");
    };
    if (image_name.has_root_name() || image_name.has_root_directory()) throw refuse("is an absolute path");
    const std::filesystem::path normal = image_name.lexically_normal();
    if (normal.empty() || !normal.has_filename() || normal == ".") throw refuse("names no file");
    if (*normal.begin() == "..") throw refuse("leaves the output folder");
    // Checked here, whether or not the folders exist yet, rather than found by the writer after
    // the render: a part longer than a file name may be, a path longer than a path may be.
    const auto unwritable = [&](const std::string& why) {
        return LoadError(scene_file, element, quoted + " cannot be written under --output-dir: " + why);
    };
    for (const std::filesystem::path& component : normal)
        if (component.native().size() > NAME_MAX)
            throw unwritable("a part of it is longer than the " + std::to_string(NAME_MAX) + " bytes of a file name");
    if ((output_dir / normal).native().size() >= PATH_MAX)
        throw unwritable("the path is longer than the " + std::to_string(PATH_MAX - 1) + " bytes of a path");

    // A symbolic link inside the folder (`out/link -> /etc`) leaves it too: every link on the way
    // must resolve, and resolve inside the folder. A dangling link is refused: the writer would
    // follow it wherever it comes to point.
    std::error_code error;
    const std::filesystem::path folder = std::filesystem::weakly_canonical(output_dir, error);
    if (error) throw LoadError(output_dir, "", "cannot resolve the output folder: " + error.message());
    const auto inside_folder = [&](const std::filesystem::path& real) {
        const std::filesystem::path relative = real.lexically_relative(folder);
        return !relative.empty() && *relative.begin() != "..";
    };
    std::filesystem::path prefix = output_dir;
    for (const std::filesystem::path& component : normal) {
        prefix /= component;
        if (!std::filesystem::is_symlink(std::filesystem::symlink_status(prefix, error))) continue;
        const std::filesystem::path real = std::filesystem::canonical(prefix, error);
        if (error) throw refuse("passes through a link that points nowhere");
        if (!inside_folder(real)) throw refuse("leaves the output folder through a link");
    }
    // The system's own refusals are said as such, not as leaving the folder.
    const std::filesystem::path resolved = std::filesystem::weakly_canonical(output_dir / normal, error);
    if (error) throw unwritable(error.message());
    if (!inside_folder(resolved)) throw refuse("leaves the output folder");
    return output_dir / normal;
}

// Creates `output_dir` if it is missing and proves that a file can be written in it (one is
// created and removed), or throws a LoadError naming it and the system's reason. prism calls it
// once the scene has loaded and before the render, which may take hours: a file in the
// folder's place, a parent that cannot hold folders or a folder without write permission were
// found only when the first image was written, after every camera had rendered. A scene that
// then fails leaves the folder, and nothing in it.
inline void prepare_output_folder(const std::filesystem::path& output_dir) {
    const std::filesystem::path folder = output_dir.empty() ? std::filesystem::path(".") : output_dir;
    std::error_code error;
    std::filesystem::create_directories(folder, error);
    if (error) throw LoadError(folder, "", "cannot create the output folder: " + error.message());
    if (!std::filesystem::is_directory(folder, error))
        throw LoadError(folder, "", "cannot be the output folder: it is not a folder");
    const std::filesystem::path probe = folder / (".prism-probe." + std::to_string(::getpid()) + ".tmp");
    {
        std::ofstream file(probe, std::ios::binary);
        if (!file) {
            const int reason = errno;
            throw LoadError(folder, "", "cannot write images in the output folder: " +
                                            std::error_code(reason, std::generic_category()).message());
        }
    }
    std::filesystem::remove(probe, error);
}

}  // namespace prism::io
