// The scene interpreter's vocabulary for reading one element: faults that name the file and the
// element (LoadError), numbers in every spelling the course's files use, ids, keywords, and the
// list of elements left unread. Shared by scene_loader.hpp and its section readers (*_loader.hpp).
#pragma once

#include <prism/io/element.hpp>
#include <prism/io/load_error.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <set>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace prism::io::detail::scene_loader {

// The blank-separated words of `text`, found as they are read: a list of millions of numbers
// (inline VertexData, Faces) is not first copied into as many views, 16 bytes a word.
class Words {
public:
    class iterator {
    public:
        using value_type = std::string_view;
        using difference_type = std::ptrdiff_t;
        iterator() = default;
        iterator(std::string_view text, std::size_t from) : text_(text) { find(from); }
        std::string_view operator*() const { return text_.substr(start_, end_ - start_); }
        iterator& operator++() {
            find(end_);
            return *this;
        }
        iterator operator++(int) {
            iterator before = *this;
            ++*this;
            return before;
        }
        bool operator==(const iterator& other) const { return start_ == other.start_; }

    private:
        void find(std::size_t from) {
            while (from < text_.size() && Element::is_blank(text_[from])) ++from;
            start_ = end_ = from;
            while (end_ < text_.size() && !Element::is_blank(text_[end_])) ++end_;
        }
        std::string_view text_;
        std::size_t start_ = 0, end_ = 0;  // the word's bytes; start_ == text_.size() at the end
    };

    explicit Words(std::string_view text) : text_(text) {}
    iterator begin() const { return {text_, 0}; }
    iterator end() const { return {text_, text_.size()}; }
    std::size_t count() const {
        std::size_t words = 0;
        for (iterator word = begin(), last = end(); word != last; ++word) ++words;
        return words;
    }

private:
    std::string_view text_;
};

inline Words split_words(std::string_view text) { return Words(text); }

inline std::string_view trim(std::string_view text) {
    while (!text.empty() && Element::is_blank(text.front())) text.remove_prefix(1);
    while (!text.empty() && Element::is_blank(text.back())) text.remove_suffix(1);
    return text;
}

// Appended piece by piece: `"\"" + std::string(text)` draws GCC 12's false -Wrestrict warning
// (GCC bug 105651) wherever the optimiser inlines it.
inline std::string in_quotes(std::string_view text) {
    std::string quoted;
    quoted.reserve(text.size() + 2);
    quoted += '"';
    quoted += text;
    quoted += '"';
    return quoted;
}
class ElementReader {
public:
    explicit ElementReader(const std::filesystem::path& file) : file_(file), folder_(file.parent_path()) {}

    const std::filesystem::path& file() const { return file_; }
    // Every file a scene names (PLY, binary data, images) is relative to the scene file's folder.
    const std::filesystem::path& folder() const { return folder_; }

    // ---- faults -----------------------------------------------------------------------------

    [[noreturn]] void fail(const Element& element, const std::string& message) const {
        throw LoadError(file_, element.where(), message);
    }

    const Element& required(const Element& parent, std::string_view name) const {
        const Element* child = parent.child(name);
        if (child == nullptr) fail(parent, "missing <" + std::string(name) + ">");
        return *child;
    }

    const std::string& required_attribute(const Element& element, std::string_view name) const {
        const std::string* value = element.attribute(name);
        if (value == nullptr) fail(element, "missing attribute " + std::string(name));
        return *value;
    }

    void check_single(const Element& parent, std::initializer_list<std::string_view> names) const {
        for (std::string_view name : names) {
            const auto count = std::count_if(parent.children.begin(), parent.children.end(),
                                             [&](const Element& c) { return c.name == name; });
            if (count > 1) fail(parent, "<" + std::string(name) + "> is given " + std::to_string(count) + " times");
        }
    }

    // Later topics' elements are skipped, but named, so the renderer can say what it leaves out.
    void note_unsupported(const Element& element) {
        if (element.is_empty()) return;  // `<Textures></Textures>` asks for nothing
        if (unsupported_seen_.insert(element.name).second) unsupported_.push_back(element.name);
    }

    void note_unsupported_children(const Element& parent, std::initializer_list<std::string_view> known) {
        for (const Element& child : parent.children)
            if (std::find(known.begin(), known.end(), child.name) == known.end()) note_unsupported(child);
    }

    // ---- values -----------------------------------------------------------------------------

    double parse_number(const Element& element, std::string_view word) const {
        std::string_view digits = word;
        if (digits.size() > 1 && digits.front() == '+') digits.remove_prefix(1);  // from_chars refuses '+'
        double value = 0.0;
        const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
        if (error == std::errc::result_out_of_range) fail(element, in_quotes(word) + " is out of the range of a double");
        if (error != std::errc() || end != digits.data() + digits.size())
            fail(element, in_quotes(word) + " is not a number");
        if (!std::isfinite(value)) fail(element, in_quotes(word) + " is not a finite number");
        return value;
    }

    std::vector<double> numbers(const Element& element) const {
        const Words words = split_words(element.text);
        std::vector<double> values;
        values.reserve(words.count());  // counted first: the list is not grown and copied as it is read
        for (std::string_view word : words) values.push_back(parse_number(element, word));
        return values;
    }

    std::vector<double> numbers(const Element& element, std::size_t count) const {
        std::vector<double> values = numbers(element);
        if (values.size() != count)
            fail(element, "expected " + std::to_string(count) + (count == 1 ? " number" : " numbers") + ", found " +
                              std::to_string(values.size()));
        return values;
    }

    double number(const Element& element) const { return numbers(element, 1)[0]; }

    double non_negative(const Element& element) const {
        const double value = number(element);
        if (value < 0.0) fail(element, "must not be negative");
        return value;
    }

    scene::Vec3 vector3(const Element& element) const {
        const std::vector<double> v = numbers(element, 3);
        return {v[0], v[1], v[2]};
    }

    // Integers may be written as such or as an integral number ("800", "8e2").
    long long parse_integer(const Element& element, std::string_view word) const {
        long long value = 0;
        const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
        if (error == std::errc() && end == word.data() + word.size()) return value;
        const double real = parse_number(element, word);
        if (real != std::floor(real) || std::abs(real) > 9.0e15) fail(element, in_quotes(word) + " is not an integer");
        return static_cast<long long>(real);
    }

    std::vector<long long> integers(const Element& element) const {
        const Words words = split_words(element.text);
        std::vector<long long> values;
        values.reserve(words.count());
        for (std::string_view word : words) values.push_back(parse_integer(element, word));
        return values;
    }

    long long integer(const Element& element) const {
        const Words words = split_words(element.text);
        if (const std::size_t count = words.count(); count != 1)
            fail(element, "expected 1 integer, found " + std::to_string(count) + " values");
        return parse_integer(element, *words.begin());
    }

    long long integer_at_least(const Element& element, long long minimum) const {
        const long long value = integer(element);
        if (value < minimum) fail(element, "must be at least " + std::to_string(minimum) + ", not " + std::to_string(value));
        return value;
    }

    // An integer the renderer must not be asked beyond prism's limit `maximum` (limits.hpp);
    // `remedy`, when given, says how a user may raise it.
    long long integer_within_limit(const Element& element, long long minimum, long long maximum,
                                   const std::string& remedy = {}) const {
        const long long value = integer_at_least(element, minimum);
        if (value > maximum)
            fail(element, std::to_string(value) + " is over prism's limit of " + std::to_string(maximum) +
                              (remedy.empty() ? std::string() : " (" + remedy + ")"));
        return value;
    }

    long long integer_attribute(const Element& element, std::string_view name, long long fallback) const {
        const std::string* value = element.attribute(name);
        if (value == nullptr) return fallback;
        const std::string_view word = trim(*value);
        long long result = 0;
        const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), result);
        if (error != std::errc() || end != word.data() + word.size() || word.empty())
            fail(element, "attribute " + std::string(name) + "=" + in_quotes(*value) + " is not an integer");
        return result;
    }

    bool boolean_attribute(const Element& element, std::string_view name, bool fallback) const {
        const std::string* value = element.attribute(name);
        if (value == nullptr) return fallback;
        const std::string_view word = trim(*value);
        if (word == "true") return true;
        if (word == "false") return false;
        fail(element, "attribute " + std::string(name) + "=" + in_quotes(*value) + " must be \"true\" or \"false\"");
    }

    std::string text_of(const Element& element) const { return std::string(trim(element.text)); }

    std::string required_id(const Element& element) const {
        return std::string(trim(required_attribute(element, "id")));
    }

    std::string id_of(const Element& element) const {
        const std::string* id = element.attribute("id");
        return id != nullptr ? std::string(trim(*id)) : std::string();
    }


    // A keyword among `choices` (a DecalMode, an Interpolation, ...); anything else is a fault that
    // lists what the element accepts. `what` names the value in the message ("decal mode").
    template <class Value>
    Value keyword(const Element& element, std::string_view what, std::string_view word,
                  std::initializer_list<std::pair<std::string_view, Value>> choices) const {
        std::string expected;
        std::size_t i = 0;
        for (const auto& [name, value] : choices) {
            if (trim(word) == name) return value;
            expected += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + std::string(name);
            ++i;
        }
        fail(element, "unknown " + std::string(what) + " " + in_quotes(trim(word)) + " (expected " + expected + ")");
    }

    template <class Value>
    Value keyword(const Element& element, std::string_view what,
                  std::initializer_list<std::pair<std::string_view, Value>> choices) const {
        return keyword(element, what, element.text, choices);
    }

    double positive(const Element& element) const {
        const double value = number(element);
        if (!(value > 0.0)) fail(element, "must be positive");
        return value;
    }

    // The elements met that this version does not render, one entry per name, in file order.
    std::vector<std::string> take_unsupported() { return std::move(unsupported_); }

protected:
    std::filesystem::path file_;
    std::filesystem::path folder_;

private:
    std::vector<std::string> unsupported_;
    std::set<std::string> unsupported_seen_;
};

}  // namespace prism::io::detail::scene_loader
