#include "weft/core/json_file.h"

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"

namespace weft {

namespace {

using nlohmann::json;

// A syntax error's detail is cut here: a message should not echo megabytes.
constexpr size_t kMaxSyntaxDetail = 200;

// "FILE:LINE:COLUMN" of the byte at `index` (1-based line and column; the
// end of the text when index is past it).
std::string textPosition(std::string_view text, const std::string& source, size_t index) {
    index = std::min(index, text.size());
    const std::string_view before = text.substr(0, index);
    const size_t line = 1 + static_cast<size_t>(std::count(before.begin(), before.end(), '\n'));
    const size_t lineStart = before.rfind('\n');
    const size_t column = index - (lineStart == std::string_view::npos ? 0 : lineStart + 1) + 1;
    return source + ":" + std::to_string(line) + ":" + std::to_string(column);
}

// nlohmann's message without its "[json.exception...] parse error at line L,
// column C: " prefix (we print our own position), cut to a sane length.
std::string syntaxDetail(const std::string& what) {
    std::string detail = what;
    if (!detail.empty() && detail.front() == '[') {
        const size_t close = detail.find("] ");
        if (close != std::string::npos) detail.erase(0, close + 2);
    }
    if (detail.rfind("parse error", 0) == 0) {
        const size_t colon = detail.find(": ");
        if (colon != std::string::npos) detail.erase(0, colon + 2);
    }
    if (detail.size() > kMaxSyntaxDetail) detail = detail.substr(0, kMaxSyntaxDetail) + "...";
    return detail;
}

// Rejects nesting deeper than kMaxNesting before the parser builds the tree.
void checkNesting(std::string_view text, const std::string& source) {
    int depth = 0;
    bool inString = false, escaped = false;
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (inString) {
            if (escaped) {
                escaped = false;
            } else if (c == '\\') {
                escaped = true;
            } else if (c == '"') {
                inString = false;
            }
        } else if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            if (++depth > kMaxJsonNesting)
                throw InputError(textPosition(text, source, i) + ": JSON nested deeper than " +
                                 std::to_string(kMaxJsonNesting) + " levels");
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
}

// Builds the tree like nlohmann's own DOM parser, but a key that repeats in
// one object is an error (the default keeps the last silently) and the byte
// position of a syntax error is kept for a line:column message.
class StrictSax final : public nlohmann::json_sax<json> {
  public:
    bool null() override { return add(json(nullptr)); }
    bool boolean(bool v) override { return add(json(v)); }
    bool number_integer(number_integer_t v) override { return add(json(v)); }
    bool number_unsigned(number_unsigned_t v) override { return add(json(v)); }
    bool number_float(number_float_t v, const string_t&) override { return add(json(v)); }
    bool string(string_t& v) override { return add(json(std::move(v))); }
    bool binary(binary_t& v) override { return add(json::binary(std::move(v))); }

    bool start_object(std::size_t) override { return open(json::object()); }
    bool start_array(std::size_t) override { return open(json::array()); }
    bool end_object() override { return close(); }
    bool end_array() override { return close(); }

    bool key(string_t& k) override {
        Frame& top = stack_.back();
        auto& object = top.container->get_ref<json::object_t&>();
        if (object.count(k) != 0) {
            duplicate_ = "duplicate key " + jsonString(k);
            duplicatePath_ = openPath();
            return false;
        }
        top.slot = &object[k];
        top.key = std::move(k);
        return true;
    }

    // position counts the bytes read. A syntax error stops on the offending
    // byte; a number overflow (406) is reported after the number, whose text
    // is lastToken: point at its first digit instead.
    bool parse_error(std::size_t position, const std::string& lastToken,
                     const nlohmann::json::exception& e) override {
        const bool overflow = e.id == 406 && lastToken.size() <= position;
        errorIndex_ = overflow ? position - lastToken.size() : (position == 0 ? 0 : position - 1);
        errorDetail_ = syntaxDetail(e.what());
        return false;
    }

    json& root() { return root_; }
    // "duplicate key \"k\"" ("" for none), and the JSON path of its object.
    const std::string& duplicate() const { return duplicate_; }
    const std::string& duplicatePath() const { return duplicatePath_; }
    size_t errorIndex() const { return errorIndex_; }
    const std::string& errorDetail() const { return errorDetail_; }

  private:
    struct Frame {
        json* container;
        json* slot = nullptr;  // object: the value of the current key
        std::string key;
    };

    // Places a value in the open container (or as the root); `placed` is where it landed.
    bool add(json v, json** placed = nullptr) {
        json* at = &root_;
        if (stack_.empty()) {
            root_ = std::move(v);
        } else if (Frame& top = stack_.back(); top.container->is_array()) {
            top.container->push_back(std::move(v));
            at = &top.container->back();
        } else {
            *top.slot = std::move(v);
            at = top.slot;
        }
        if (placed != nullptr) *placed = at;
        return true;
    }
    bool open(json container) {
        json* placed = nullptr;
        add(std::move(container), &placed);
        stack_.push_back(Frame{placed, nullptr, {}});
        return true;
    }
    bool close() {
        stack_.pop_back();
        return true;
    }
    // JSON path of the innermost open container ("" for the root).
    std::string openPath() const {
        std::string path;
        for (size_t i = 0; i + 1 < stack_.size(); ++i) {
            const Frame& f = stack_[i];
            path = f.container->is_array() ? jsonIndexPath(path, f.container->size() - 1)
                                           : jsonChildPath(path, f.key);
        }
        return path;
    }

    json root_;
    std::vector<Frame> stack_;
    std::string duplicate_, duplicatePath_;
    size_t errorIndex_ = 0;
    std::string errorDetail_;
};

}  // namespace

nlohmann::json parseJsonText(std::string_view text, const std::string& source) {
    checkNesting(text, source);
    StrictSax sax;
    if (!json::sax_parse(text.begin(), text.end(), &sax)) {
        if (!sax.duplicate().empty()) throwJsonError(source, sax.duplicatePath(), sax.duplicate());
        throw InputError(textPosition(text, source, sax.errorIndex()) +
                         ": malformed JSON: " + sax.errorDetail());
    }
    return std::move(sax.root());
}

nlohmann::json readJsonFile(const std::string& path) { return parseJsonText(readFile(path), path); }

}  // namespace weft
