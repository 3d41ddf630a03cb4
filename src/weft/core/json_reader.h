// weft/core/json_reader.h — one strict reader for the JSON objects of weft's input files.
//
// Fiber parameters, the fit configuration, model.json and scene.json are all
// read through JsonObjectReader, so that their errors have one shape and one
// wording (InputError; <path> is the JSON path of the value, "yarns[1].plies",
// and is left out with its colon at the top level):
//   <source>: <path>: unknown key "k" (allowed: a, b, c)
//   <source>: <path>: missing key "k"
//   <source>: <path>: expected a number in [0, 1], got the string "x"
//   <source>: <path> = 1.5 is out of range: allowed [0, 1]
// <source> names the input: a file, or "scene" / "fiber parameters" for a
// document built in memory. Non-finite numbers (not JSON, but possible in a
// document built in memory, e.g. from Python) are rejected everywhere.
// Duplicate keys are the parser's business (readJsonFile keeps the last, the
// scene parser rejects them): the reader sees the parsed object.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace weft {

// An interval of allowed numbers and its text in messages ("[0, 1]", "> 0",
// "(0, 90] degrees"). The default is any finite number.
class NumberRange {
  public:
    NumberRange() = default;
    static NumberRange closed(double lo, double hi);      // [lo, hi]
    static NumberRange open(double lo, double hi);        // (lo, hi)
    static NumberRange openClosed(double lo, double hi);  // (lo, hi]
    static NumberRange closedOpen(double lo, double hi);  // [lo, hi)
    static NumberRange atLeast(double lo);                // >= lo
    static NumberRange greaterThan(double lo);            // > lo
    // The same range with a unit or remark after its text: "(0, 90] degrees".
    NumberRange with(std::string note) const;

    bool contains(double x) const;  // false for NaN
    std::string text() const;       // "" for any finite number
    // "in [0, 1]", "> 0", "" (after "expected a number").
    std::string expectation() const;

  private:
    double lo_ = -std::numeric_limits<double>::infinity();
    double hi_ = std::numeric_limits<double>::infinity();
    bool openLo_ = false, openHi_ = false;
    std::string note_;
};

// Allowed integers [lo, hi] and a remark after the text ("[0, 1024] (0: all cores)").
// The default is any int64_t.
struct IntegerRange {
    IntegerRange() = default;
    IntegerRange(int64_t lo_, int64_t hi_, std::string note_ = {})
        : lo(lo_), hi(hi_), note(std::move(note_)) {}

    int64_t lo = std::numeric_limits<int64_t>::min();
    int64_t hi = std::numeric_limits<int64_t>::max();
    std::string note;

    bool any() const;
    std::string text() const;  // "[lo, hi]" and the note
};

// How an integer may be written. Strict: a JSON integer (64, not 64.0).
// WholeNumbers: also a number with no fractional part (64.0, 6.4e1), as
// scene.json documents.
enum class JsonIntegers { Strict, WholeNumbers };

// "<source>: <path>: <message>" ("<source>: <message>" when path is empty).
[[noreturn]] void throwJsonError(std::string_view source, std::string_view path,
                                 std::string_view message);
// "<source>: <path> = <value> is out of range: allowed <allowed>".
[[noreturn]] void throwJsonOutOfRange(std::string_view source, std::string_view path,
                                      std::string_view value, std::string_view allowed);
// A value that is not under a key (an element of a nested array): a finite
// JSON number in `range`, with the reader's messages.
double readJsonNumber(const nlohmann::json& v, std::string_view source, const std::string& path,
                      const NumberRange& range = {});

// A JSON object being read: typed, range-checked getters by key, each error
// naming the source, the JSON path and what was allowed. Holds a reference to
// the object: it must outlive the reader.
class JsonObjectReader {
  public:
    // InputError unless `value` is an object. `path` is its JSON path ("" at
    // the top level); `integers` applies to this object and its children.
    JsonObjectReader(const nlohmann::json& value, std::string source, std::string path = {},
                     JsonIntegers integers = JsonIntegers::Strict);

    // Rejects any key not in `allowed`, listing them. Call it before reading
    // (after a key that decides the others, such as a light's "type"), so
    // that a misspelt required key reads as the unknown key it is rather than
    // as a missing one. Reading a key outside `allowed` afterwards is a bug
    // (std::logic_error).
    void allowKeys(std::initializer_list<std::string_view> allowed);

    bool has(std::string_view key) const;
    // Present and null (an optional block written as null).
    bool isNull(std::string_view key) const;
    // The value under `key`; InputError "missing key" when absent. Every getter
    // below requires its key the same way: test has() first for an optional one.
    const nlohmann::json& value(std::string_view key) const;

    // A finite number in `range`.
    double number(std::string_view key, const NumberRange& range = {}) const;
    // An integer in `range` (written as `integers` allows).
    int64_t integer(std::string_view key, const IntegerRange& range = {}) const;
    // An integer in [0, 2^64 - 1] (a seed).
    uint64_t unsignedInteger(std::string_view key) const;
    bool boolean(std::string_view key) const;
    std::string string(std::string_view key) const;
    // A string among `allowed`; returns its index.
    size_t oneOf(std::string_view key, std::initializer_list<std::string_view> allowed) const;
    size_t oneOf(std::string_view key, std::span<const std::string_view> allowed) const;
    // An array of exactly `count` finite numbers in `range`; `what` names the
    // elements in messages ("(r, g, b)").
    std::vector<double> numbers(std::string_view key, size_t count, const NumberRange& range = {},
                                std::string_view what = {}) const;
    // An array of minCount to maxCount integers in `range`.
    std::vector<int64_t> integers(std::string_view key, size_t minCount, size_t maxCount,
                                  const IntegerRange& range = {}, std::string_view what = {}) const;
    // The object under `key` (path "this.key"), with `allowed` keys when given.
    JsonObjectReader object(std::string_view key) const;
    JsonObjectReader object(std::string_view key,
                            std::initializer_list<std::string_view> allowed) const;
    // An array of objects (paths "this.key[i]"); their keys are not checked yet.
    std::vector<JsonObjectReader> objects(std::string_view key) const;

    const std::string& source() const { return source_; }
    const std::string& path() const { return path_; }
    // JSON path of the value under `key`.
    std::string pathOf(std::string_view key) const;
    // InputError about this object, or about the value under `key`.
    [[noreturn]] void fail(std::string_view message) const;
    [[noreturn]] void fail(std::string_view key, std::string_view message) const;
    // "<source>: <path of key> = <value> is out of range: allowed <allowed>".
    [[noreturn]] void failOutOfRange(std::string_view key, std::string_view value,
                                     std::string_view allowed) const;

  private:
    void checkDeclared(std::string_view key) const;
    int64_t integerAt(const nlohmann::json& v, const std::string& path,
                      const IntegerRange& range) const;

    const nlohmann::json* object_;
    std::string source_;
    std::string path_;
    JsonIntegers integers_;
    std::vector<std::string> allowed_;
    bool keysChecked_ = false;
};

}  // namespace weft
