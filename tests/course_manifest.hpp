// The course data the tests read from ../shared (PRISM_SHARED_DIR): its folder and the rows of
// its MANIFEST.tsv (topic, scene, format, path relative to the folder, unresolved assets).
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace prism_test {

inline const std::filesystem::path course_folder = std::filesystem::path(PRISM_SHARED_DIR) / "ceng795";

struct ManifestRow {
    std::string topic, scene, format, path, unresolved;
};

// Empty when the manifest is absent (the tests that need it then report themselves skipped).
inline std::vector<ManifestRow> read_manifest() {
    std::ifstream stream(course_folder / "MANIFEST.tsv");
    std::vector<ManifestRow> rows;
    std::string line;
    std::getline(stream, line);  // the header
    while (std::getline(stream, line)) {
        if (line.empty()) continue;
        std::vector<std::string> fields;
        std::size_t start = 0;
        for (std::size_t tab = line.find('\t'); tab != std::string::npos; tab = line.find('\t', start)) {
            fields.push_back(line.substr(start, tab - start));
            start = tab + 1;
        }
        fields.push_back(line.substr(start));
        fields.resize(7);
        rows.push_back({fields[0], fields[1], fields[2], fields[3], fields[6]});
    }
    return rows;
}

}  // namespace prism_test
