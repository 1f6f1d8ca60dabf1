// prism-suite's HTML report (--report DIR): one page, DIR/report.html, with no network and no
// outside script or style, and the images it shows beside it in DIR/images/. Each row shows the
// render, the reference and a heat map of their difference as the suite compared them (the
// 8-bit values of its PSNR), so what a reader sees is what was judged.
#pragma once

#include <prism/image/image.hpp>
#include <prism/image/image_io.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace prism::suite {

// One line of the suite's table, and one row of the report.
struct Row {
    std::string topic, scene, format, image = "-", size = "-", seconds = "-", psnr = "-", off = "-", status, note;
};

// The images of one row as they were compared: interleaved 8-bit RGB of the render's size.
// `reference` is empty when the row has none (no reference, or none it could be compared with).
struct ComparedImages {
    int width = 0, height = 0;
    std::vector<std::uint8_t> render, reference;
};

// The heat map of two compared images: each pixel coloured by its largest channel difference
// d (in 8-bit levels). Black where equal; blue for 1-8, within the tolerance of the "off" share;
// yellow at 9 through red at 64 and beyond, the pixels that the share counts.
inline std::vector<std::uint8_t> difference_heat_map(const std::vector<std::uint8_t>& a,
                                                     const std::vector<std::uint8_t>& b) {
    std::vector<std::uint8_t> map(a.size());
    for (std::size_t i = 0; i + 2 < a.size() && i + 2 < b.size(); i += 3) {
        int d = 0;
        for (std::size_t c = 0; c < 3; ++c) d = std::max(d, std::abs(int(a[i + c]) - int(b[i + c])));
        std::uint8_t r = 0, g = 0, blue = 0;
        if (d > 8) {
            const double t = std::min(1.0, double(d - 9) / (64 - 9));
            r = 255;
            g = std::uint8_t(std::lround(230.0 * (1.0 - t)));
        } else if (d > 0) {
            blue = std::uint8_t(80 + 20 * d);
        }
        map[i] = r;
        map[i + 1] = g;
        map[i + 2] = blue;
    }
    return map;
}

inline std::string html_escaped(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
        switch (c) {
            case '&': out += "&amp;"; break;
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '"': out += "&quot;"; break;
            case '\'': out += "&#39;"; break;
            default: out += c;
        }
    }
    return out;
}

class Report {
public:
    // Creates DIR and DIR/images and proves that a file can be written there, so that a run
    // that cannot write its report fails before it renders; throws std::runtime_error saying why.
    explicit Report(std::filesystem::path folder) : folder_(std::move(folder)) {
        namespace fs = std::filesystem;
        if (folder_.empty()) throw std::runtime_error("--report needs a folder");
        std::error_code error;
        fs::create_directories(folder_ / "images", error);
        if (error) throw std::runtime_error("--report " + folder_.string() + ": cannot create the folder: " + error.message());
        const fs::path probe = folder_ / ".prism-suite-write-test";
        {
            std::ofstream out(probe);
            out << "probe\n";
            if (!out.good()) throw std::runtime_error("--report " + folder_.string() + ": cannot write in the folder");
        }
        fs::remove(probe, error);
    }

    const std::filesystem::path& page() const { return page_; }

    // Adds a row; its images (if any) are written to DIR/images/ at once, so the report's memory
    // does not grow with the run. A failed image write is noted in the row, not thrown.
    void add(Row row, const std::optional<ComparedImages>& images) {
        Entry entry{std::move(row), {}, {}, {}, 0, 0};
        if (images && !images->render.empty()) {
            char stem[32];
            std::snprintf(stem, sizeof stem, "images/%04zu", entries_.size() + 1);
            entry.width = images->width;
            entry.height = images->height;
            try {
                entry.render = std::string(stem) + "-render.png";
                write_8bit_png(folder_ / entry.render, *images, images->render);
                if (images->reference.size() == images->render.size()) {
                    entry.reference = std::string(stem) + "-reference.png";
                    entry.difference = std::string(stem) + "-difference.png";
                    write_8bit_png(folder_ / entry.reference, *images, images->reference);
                    write_8bit_png(folder_ / entry.difference, *images,
                                   difference_heat_map(images->render, images->reference));
                }
            } catch (const std::exception& error) {
                entry.render = entry.reference = entry.difference = "";
                entry.row.note += std::string(entry.row.note.empty() ? "" : "; ") + "report image: " + error.what();
            }
        }
        entries_.push_back(std::move(entry));
    }

    // Writes DIR/report.html (to a temporary sibling, then renamed); throws std::runtime_error.
    void write(const std::string& heading) const {
        namespace fs = std::filesystem;
        const fs::path temporary = folder_ / ".report.html.tmp";
        {
            std::ofstream out(temporary);
            out << html(heading);
            if (!out.good()) throw std::runtime_error(page_.string() + ": cannot write the report");
        }
        std::error_code error;
        fs::rename(temporary, page_, error);
        if (error) throw std::runtime_error(page_.string() + ": cannot write the report: " + error.message());
    }

private:
    struct Entry {
        Row row;
        std::string render, reference, difference;  // paths relative to the page; "" when absent
        int width, height;
    };

    static void write_8bit_png(const std::filesystem::path& path, const ComparedImages& size,
                               const std::vector<std::uint8_t>& bytes) {
        // Whole numbers 0-255 survive the PNG writer's clamp-and-truncate unchanged.
        Image image(size.width, size.height);
        for (std::size_t i = 0; i < image.pixels.size(); ++i)
            image.pixels[i] = glm::vec3(bytes[3 * i], bytes[3 * i + 1], bytes[3 * i + 2]);
        write_image(path, image);
    }

    static bool passed(const Row& row) { return row.status == "PASS"; }
    static bool failed(const Row& row) { return row.status == "FAIL" || row.status == "ERROR"; }

    // The PSNR distribution as bars: one per 10 dB, identical images on their own.
    std::string distribution() const {
        static const char* const labels[] = {"< 20", "20-30", "30-40", "40-50", "50-60", "60-80", "≥ 80", "identical"};
        int counts[8] = {};
        std::vector<double> values;
        for (const Entry& entry : entries_) {
            if (entry.row.psnr == "-") continue;
            const double db = entry.row.psnr == "inf" ? INFINITY : std::stod(entry.row.psnr);
            values.push_back(db);
            const int bin = std::isinf(db) ? 7 : db < 20 ? 0 : db < 60 ? int(db / 10) - 1 : db < 80 ? 5 : 6;
            ++counts[bin];
        }
        if (values.empty()) return "<p>No image was compared: no PSNR to show.</p>\n";
        std::sort(values.begin(), values.end());
        const auto db = [](double value) { return std::isinf(value) ? std::string("identical") : fixed(value) + " dB"; };
        const std::size_t n = values.size();
        std::string out = "<p>PSNR of " + std::to_string(n) + (n == 1 ? " image" : " images") + ": lowest " +
                          db(values.front()) + ", median " + db(values[(n - 1) / 2]) + ", highest " + db(values.back()) +
                          ".</p>\n<table class=\"histogram\" aria-label=\"PSNR distribution\">\n";
        const int largest = *std::max_element(std::begin(counts), std::end(counts));
        for (int bin = 0; bin < 8; ++bin) {
            char width[16];  // the largest bin is 20em long
            std::snprintf(width, sizeof width, "%.1fem", largest ? 20.0 * counts[bin] / largest : 0.0);
            out += "<tr><th>" + std::string(labels[bin]) + "</th><td><span class=\"bar\" style=\"width:" + width +
                   "\"></span> " + std::to_string(counts[bin]) + "</td></tr>\n";
        }
        return out + "</table>\n";
    }

    static std::string fixed(double value) {
        char text[32];
        std::snprintf(text, sizeof text, "%.1f", value);
        return text;
    }

    static std::string image_cell(const std::string& path, const Entry& entry, const char* what) {
        if (path.empty()) return "<td class=\"none\">-</td>";
        const std::string size = " width=\"" + std::to_string(entry.width) + "\" height=\"" + std::to_string(entry.height) + "\"";
        return "<td><a href=\"" + path + "\"><img src=\"" + path + "\" alt=\"" + what + "\"" + size + "></a></td>";
    }

    std::string html(const std::string& heading) const {
        int pass = 0, fail = 0, informational = 0;
        std::map<std::string, int> topics;
        for (const Entry& entry : entries_) {
            passed(entry.row) ? ++pass : failed(entry.row) ? ++fail : ++informational;
            ++topics[entry.row.topic];
        }
        std::string out = R"(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>prism-suite report</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
body { font: 14px/1.4 system-ui, sans-serif; margin: 1.5em; color: #1b1b1b; background: #fafafa; }
h1 { font-size: 1.4em; margin: 0 0 .3em; }
.counts span { display: inline-block; margin-right: 1.5em; font-size: 1.15em; }
.pass { color: #17702b; } .fail { color: #b3121b; } .info { color: #555; }
table.histogram th { text-align: right; font-weight: normal; padding-right: .6em; white-space: nowrap; }
table.histogram td { white-space: nowrap; }
.bar { display: inline-block; height: .9em; background: #4a6fa5; vertical-align: middle; }
#controls { margin: 1em 0; } #controls label { margin-right: 1.5em; }
#rows { border-collapse: collapse; background: #fff; }
#rows th, #rows td { border: 1px solid #ddd; padding: 4px 6px; vertical-align: top; }
#rows thead th { background: #eee; position: sticky; top: 0; }
#rows img { max-width: 220px; height: auto; display: block; image-rendering: pixelated; }
#rows td.number { text-align: right; font-variant-numeric: tabular-nums; }
#rows td.none { color: #999; text-align: center; vertical-align: middle; }
button.sort { font: inherit; font-weight: bold; border: 0; background: none; cursor: pointer; padding: 0; }
button.sort[data-order="ascending"]::after { content: " ▲"; } button.sort[data-order="descending"]::after { content: " ▼"; }
.legend span { display: inline-block; width: 1em; height: 1em; vertical-align: middle; border: 1px solid #999; }
</style></head><body>
)";
        out += "<h1>prism-suite report</h1>\n<p>" + html_escaped(heading) + "</p>\n";
        out += "<section id=\"summary\"><p class=\"counts\"><span class=\"pass\">" + std::to_string(pass) +
               " passed</span><span class=\"fail\">" + std::to_string(fail) + " failed</span><span class=\"info\">" +
               std::to_string(informational) +
               " informational (info, rendered, skipped)</span></p>\n" + distribution() + "</section>\n";
        out += "<p class=\"legend\">Images are shown as they were compared (8-bit: clamped, or tone-mapped with "
               "the reference's exposure under --hdr). Difference, by the largest channel's difference: "
               "<span style=\"background:#000\"></span> equal, <span style=\"background:#0000e6\"></span> 1-8 levels "
               "(not counted as off), <span style=\"background:#ffe600\"></span> 9 to <span style=\"background:#ff0000\">"
               "</span> 64 or more levels (counted as off).</p>\n";
        out += "<div id=\"controls\"><label>Topic <select id=\"topic\"><option value=\"\">all</option>";
        for (const auto& [topic, count] : topics)
            out += "<option value=\"" + html_escaped(topic) + "\">" + html_escaped(topic) + " (" + std::to_string(count) + ")</option>";
        out += "</select></label><span id=\"shown\">" + std::to_string(entries_.size()) + " rows shown</span></div>\n";
        out += "<table id=\"rows\"><thead><tr><th>topic</th><th>scene</th><th>image</th><th>render</th><th>reference</th>"
               "<th>difference</th><th><button class=\"sort\" data-sort=\"psnr\">PSNR (dB)</button></th><th>off &gt; 8 (%)</th>"
               "<th><button class=\"sort\" data-sort=\"seconds\">time (s)</button></th><th>status</th><th>note</th></tr></thead>\n<tbody>\n";
        for (const Entry& entry : entries_) {
            const Row& row = entry.row;
            const std::string status_class = passed(row) ? "pass" : failed(row) ? "fail" : "info";
            const auto number = [](const std::string& value) { return value == "-" ? std::string() : value; };
            out += "<tr data-topic=\"" + html_escaped(row.topic) + "\" data-psnr=\"" + number(row.psnr) +
                   "\" data-seconds=\"" + number(row.seconds) + "\" data-status=\"" + html_escaped(row.status) + "\">";
            out += "<td>" + html_escaped(row.topic) + "</td><td>" + html_escaped(row.scene) + "." + html_escaped(row.format) +
                   "</td><td>" + html_escaped(row.image) + "<br><small>" + html_escaped(row.size) + "</small></td>";
            out += image_cell(entry.render, entry, "render") + image_cell(entry.reference, entry, "reference") +
                   image_cell(entry.difference, entry, "difference");
            out += "<td class=\"number\">" + html_escaped(row.psnr) + "</td><td class=\"number\">" + html_escaped(row.off) +
                   "</td><td class=\"number\">" + html_escaped(row.seconds) + "</td><td class=\"" + status_class + "\">" +
                   html_escaped(row.status) + "</td><td>" + html_escaped(row.note) + "</td></tr>\n";
        }
        out += "</tbody></table>\n";
        // Sorting keeps rows without a number last in either order; the topic filter hides rows.
        out += R"(<script>
(function () {
  const body = document.querySelector('#rows tbody');
  const rows = Array.from(body.rows);
  const buttons = Array.from(document.querySelectorAll('button.sort'));
  const number = (row, key) => {
    const text = row.dataset[key];
    return text === '' ? null : text === 'inf' ? Infinity : Number(text);
  };
  buttons.forEach((button) => button.addEventListener('click', () => {
    const key = button.dataset.sort;
    const descending = button.dataset.order === 'ascending';
    buttons.forEach((other) => { delete other.dataset.order; });
    button.dataset.order = descending ? 'descending' : 'ascending';
    const sorted = rows.slice().sort((a, b) => {
      const x = number(a, key), y = number(b, key);
      if (x === null || y === null) return (x === null) - (y === null);
      if (x === y) return 0;
      return (x < y ? -1 : 1) * (descending ? -1 : 1);
    });
    sorted.forEach((row) => body.appendChild(row));
  }));
  const topic = document.getElementById('topic');
  const shown = document.getElementById('shown');
  topic.addEventListener('change', () => {
    let count = 0;
    rows.forEach((row) => {
      row.hidden = topic.value !== '' && row.dataset.topic !== topic.value;
      if (!row.hidden) ++count;
    });
    shown.textContent = count + (count === 1 ? ' row shown' : ' rows shown');
  });
})();
</script>
</body></html>
)";
        return out;
    }

    std::filesystem::path folder_;
    std::filesystem::path page_ = folder_ / "report.html";
    std::vector<Entry> entries_;
};

}  // namespace prism::suite
