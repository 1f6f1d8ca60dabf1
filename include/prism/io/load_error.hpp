// The one error type every reader throws: it names the file and the element at fault, so the
// CLI can print a single line such as
//   scene.xml: <Mesh id="3">/<Material>: unknown material id "7"
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace prism::io {

class LoadError : public std::runtime_error {
public:
    LoadError(const std::filesystem::path& file, const std::string& element, const std::string& what)
        : std::runtime_error(compose(file, element, what)), file_(file), element_(element) {}

    const std::filesystem::path& file() const noexcept { return file_; }
    const std::string& element() const noexcept { return element_; }

private:
    static std::string compose(const std::filesystem::path& file, const std::string& element,
                               const std::string& what) {
        std::string message = file.string();
        if (!element.empty()) message += ": " + element;
        return message + ": " + what;
    }

    std::filesystem::path file_;
    std::string element_;
};

}  // namespace prism::io
