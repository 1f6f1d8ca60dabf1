// What the benchmark charts draw with: numbers and text for SVG, marker shapes that stay apart
// in black and white, and logarithmic axes whose lowest decade can stand for "exactly zero".
// Shared by accuracy_chart.cpp and sampling_chart.cpp, so that both charts look and read alike.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

namespace prism::bench {

inline std::string format_number(double value, int precision) {
    std::ostringstream out;
    out << std::setprecision(precision) << value;
    return out.str();
}

inline std::string escape_xml(const std::string& text) {
    std::string out;
    for (const char c : text) {
        if (c == '&') out += "&amp;";
        else if (c == '<') out += "&lt;";
        else if (c == '>') out += "&gt;";
        else out += c;
    }
    return out;
}

// A decade range for a log axis: 10^floor_decade is the bottom line (drawn as "0" where a chart
// has exact zeros), 10^top_decade the top.
struct LogAxis {
    int floor_decade, top_decade;
};

// The decades covering every positive value and at_least_top, with one empty decade between the
// smallest value and the floor, which keeps zero apart from "small".
inline LogAxis log_axis(const std::vector<double>& values, double at_least_top) {
    double smallest = at_least_top, largest = at_least_top;
    for (const double value : values)
        if (value > 0) {
            smallest = std::min(smallest, value);
            largest = std::max(largest, value);
        }
    return {int(std::floor(std::log10(smallest))) - 1, int(std::ceil(std::log10(largest)))};
}

// 10^decade written out (0.001, 10, ...), or as a percentage when the values are shares.
inline std::string decade_label(int decade, bool percent) {
    if (percent) {
        const int p = decade + 2;  // 10^decade as a percentage
        return p >= 0 ? format_number(std::pow(10.0, p), 6) + "%" : "0." + std::string(std::size_t(-p - 1), '0') + "1%";
    }
    return decade >= 0 ? format_number(std::pow(10.0, decade), 6) : "0." + std::string(std::size_t(-decade - 1), '0') + "1";
}

// One marker, drawn as an outline so that overlapping markers stay readable: circle, square,
// diamond, triangle_up, triangle_down, plus, star (an asterisk), or anything else as a cross.
inline std::string marker_svg(const std::string& shape, double x, double y, const std::string& colour) {
    const double r = 6.5;
    std::ostringstream out;
    out << std::fixed << std::setprecision(1);
    const std::string style = "fill=\"none\" stroke=\"" + colour + "\" stroke-width=\"2\"";
    if (shape == "circle") {
        out << "<circle cx=\"" << x << "\" cy=\"" << y << "\" r=\"" << r << "\" " << style << "/>";
    } else if (shape == "square") {
        out << "<rect x=\"" << x - r * 0.85 << "\" y=\"" << y - r * 0.85 << "\" width=\"" << 1.7 * r << "\" height=\""
            << 1.7 * r << "\" " << style << "/>";
    } else if (shape == "diamond") {
        out << "<path d=\"M" << x << "," << y - r * 1.2 << " L" << x + r << "," << y << " L" << x << "," << y + r * 1.2
            << " L" << x - r << "," << y << " Z\" " << style << "/>";
    } else if (shape == "triangle_up") {
        out << "<path d=\"M" << x << "," << y - r * 1.15 << " L" << x + r << "," << y + r * 0.75 << " L" << x - r << ","
            << y + r * 0.75 << " Z\" " << style << "/>";
    } else if (shape == "triangle_down") {
        out << "<path d=\"M" << x << "," << y + r * 1.15 << " L" << x + r << "," << y - r * 0.75 << " L" << x - r << ","
            << y - r * 0.75 << " Z\" " << style << "/>";
    } else if (shape == "plus") {
        out << "<path d=\"M" << x - r << "," << y << " L" << x + r << "," << y << " M" << x << "," << y - r << " L" << x
            << "," << y + r << "\" " << style << "/>";
    } else if (shape == "star") {  // an asterisk: the plus and the cross over each other
        out << "<path d=\"M" << x - r << "," << y << " L" << x + r << "," << y << " M" << x << "," << y - r << " L" << x
            << "," << y + r << " M" << x - r * 0.7 << "," << y - r * 0.7 << " L" << x + r * 0.7 << "," << y + r * 0.7
            << " M" << x - r * 0.7 << "," << y + r * 0.7 << " L" << x + r * 0.7 << "," << y - r * 0.7 << "\" " << style
            << "/>";
    } else {  // cross
        out << "<path d=\"M" << x - r << "," << y - r << " L" << x + r << "," << y + r << " M" << x - r << "," << y + r
            << " L" << x + r << "," << y - r << "\" " << style << "/>";
    }
    return out.str();
}

}  // namespace prism::bench
