#include "weft/core/json_reader.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <utility>

#include "weft/core/error.h"
#include "weft/core/json_message.h"

namespace weft {

namespace {

using nlohmann::json;

// " " + text, or nothing for an empty text.
std::string spaced(std::string_view text) {
    // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on " " + string.
    std::string out;
    if (!text.empty()) out.append(" ").append(text);
    return out;
}

// "a number", "3 numbers".
std::string counted(size_t n, std::string_view noun) {
    return std::to_string(n) + " " + std::string(noun) + (n == 1 ? "" : "s");
}

// "\"a\", \"b\"" (quoted) or "a, b" (as is).
std::string joined(std::span<const std::string_view> names, bool quoted) {
    std::string out;
    for (std::string_view n : names)
        out += (out.empty() ? "" : ", ") + (quoted ? jsonString(n) : std::string(n));
    return out;
}

}  // namespace

NumberRange NumberRange::closed(double lo, double hi) {
    NumberRange r;
    r.lo_ = lo;
    r.hi_ = hi;
    return r;
}

NumberRange NumberRange::open(double lo, double hi) {
    NumberRange r = closed(lo, hi);
    r.openLo_ = r.openHi_ = true;
    return r;
}

NumberRange NumberRange::openClosed(double lo, double hi) {
    NumberRange r = closed(lo, hi);
    r.openLo_ = true;
    return r;
}

NumberRange NumberRange::closedOpen(double lo, double hi) {
    NumberRange r = closed(lo, hi);
    r.openHi_ = true;
    return r;
}

NumberRange NumberRange::atLeast(double lo) {
    NumberRange r;
    r.lo_ = lo;
    return r;
}

NumberRange NumberRange::greaterThan(double lo) {
    NumberRange r = atLeast(lo);
    r.openLo_ = true;
    return r;
}

NumberRange NumberRange::with(std::string note) const {
    NumberRange r = *this;
    r.note_ = std::move(note);
    return r;
}

bool NumberRange::contains(double x) const {
    const bool aboveLo = openLo_ ? x > lo_ : x >= lo_;
    const bool belowHi = openHi_ ? x < hi_ : x <= hi_;
    return aboveLo && belowHi;
}

std::string NumberRange::text() const {
    const bool hasLo = std::isfinite(lo_), hasHi = std::isfinite(hi_);
    std::string out;
    if (hasLo && hasHi) {
        out = std::string(openLo_ ? "(" : "[") + formatNumber(lo_) + ", " + formatNumber(hi_) +
              (openHi_ ? ")" : "]");
    } else if (hasLo) {
        out = std::string(openLo_ ? "> " : ">= ") + formatNumber(lo_);
    } else if (hasHi) {
        out = std::string(openHi_ ? "< " : "<= ") + formatNumber(hi_);
    }
    return out + (out.empty() || note_.empty() ? "" : " " + note_);
}

std::string NumberRange::expectation() const {
    const std::string t = text();
    return std::isfinite(lo_) && std::isfinite(hi_) ? "in " + t : t;
}

bool IntegerRange::any() const {
    return lo == std::numeric_limits<int64_t>::min() && hi == std::numeric_limits<int64_t>::max();
}

std::string IntegerRange::text() const {
    std::string out = "[";
    out.append(std::to_string(lo)).append(", ").append(std::to_string(hi)).append("]");
    return out + spaced(note);
}

void throwJsonError(std::string_view source, std::string_view path, std::string_view message) {
    std::string text(source);
    text += ": ";
    if (!path.empty()) text.append(path).append(": ");
    text += message;
    throw InputError(text);
}

void throwJsonOutOfRange(std::string_view source, std::string_view path, std::string_view value,
                         std::string_view allowed) {
    std::string text(source);
    text.append(": ").append(path).append(" = ").append(value);
    text.append(" is out of range: allowed ").append(allowed);
    throw InputError(text);
}

double readJsonNumber(const json& v, std::string_view source, const std::string& path,
                      const NumberRange& range) {
    if (!v.is_number())
        throwJsonError(
            source, path,
            "expected a number" + spaced(range.expectation()) + ", got " + describeJson(v));
    const double x = v.get<double>();
    if (!std::isfinite(x))
        throwJsonError(
            source, path,
            "expected a finite number" + spaced(range.expectation()) + ", got " + formatNumber(x));
    if (!range.contains(x)) throwJsonOutOfRange(source, path, formatNumber(x), range.text());
    return x;
}

JsonObjectReader::JsonObjectReader(const json& value, std::string source, std::string path,
                                   JsonIntegers integers)
    : object_(&value), source_(std::move(source)), path_(std::move(path)), integers_(integers) {
    if (!value.is_object()) fail("expected an object, got " + describeJson(value));
}

void JsonObjectReader::allowKeys(std::initializer_list<std::string_view> allowed) {
    allowed_.assign(allowed.begin(), allowed.end());
    keysChecked_ = true;
    for (const auto& item : object_->items())
        if (std::find(allowed_.begin(), allowed_.end(), item.key()) == allowed_.end())
            fail("unknown key " + jsonString(item.key()) + " (allowed: " +
                 joined({allowed.begin(), allowed.size()}, false) + ")");
}

void JsonObjectReader::checkDeclared(std::string_view key) const {
    if (keysChecked_ && std::find(allowed_.begin(), allowed_.end(), key) == allowed_.end())
        throw std::logic_error("JsonObjectReader: key \"" + std::string(key) + "\" read at \"" +
                               path_ + "\" is not among its allowed keys");
}

bool JsonObjectReader::has(std::string_view key) const {
    checkDeclared(key);
    return object_->find(std::string(key)) != object_->end();
}

bool JsonObjectReader::isNull(std::string_view key) const {
    return has(key) && value(key).is_null();
}

const json& JsonObjectReader::value(std::string_view key) const {
    checkDeclared(key);
    const auto it = object_->find(std::string(key));
    if (it == object_->end()) fail("missing key " + jsonString(key));
    return *it;
}

std::string JsonObjectReader::pathOf(std::string_view key) const {
    return jsonChildPath(path_, key);
}

void JsonObjectReader::fail(std::string_view message) const {
    throwJsonError(source_, path_, message);
}

void JsonObjectReader::fail(std::string_view key, std::string_view message) const {
    throwJsonError(source_, pathOf(key), message);
}

void JsonObjectReader::failOutOfRange(std::string_view key, std::string_view value,
                                      std::string_view allowed) const {
    throwJsonOutOfRange(source_, pathOf(key), value, allowed);
}

double JsonObjectReader::number(std::string_view key, const NumberRange& range) const {
    return readJsonNumber(value(key), source_, pathOf(key), range);
}

int64_t JsonObjectReader::integerAt(const json& v, const std::string& path,
                                    const IntegerRange& range) const {
    const std::string expected = "expected an integer" + (range.any() ? "" : " in " + range.text());
    const auto outOfRange = [&](const std::string& value) {
        throwJsonOutOfRange(source_, path, value, range.text());
    };
    // The JSON parser reads every non-negative integer as unsigned.
    if (v.is_number_unsigned()) {
        const uint64_t u = v.get<uint64_t>();
        if (range.hi < 0 || u > static_cast<uint64_t>(range.hi) ||
            (range.lo > 0 && u < static_cast<uint64_t>(range.lo)))
            outOfRange(std::to_string(u));
        return static_cast<int64_t>(u);
    }
    if (v.is_number_integer()) {
        const int64_t x = v.get<int64_t>();
        if (x < range.lo || x > range.hi) outOfRange(std::to_string(x));
        return x;
    }
    if (v.is_number_float()) {
        const double x = v.get<double>();
        const bool whole = std::isfinite(x) && x == std::floor(x);
        if (whole && integers_ == JsonIntegers::WholeNumbers) {
            // 2^63 itself is beyond int64_t, though it compares equal to (double)INT64_MAX.
            if (x < static_cast<double>(range.lo) || x > static_cast<double>(range.hi) ||
                x >= 0x1p63)
                outOfRange(formatNumber(x));
            return static_cast<int64_t>(x);
        }
        if (whole)
            throwJsonError(
                source_, path,
                expected + ", got " + formatNumber(x) + " (written as a floating-point number)");
    }
    throwJsonError(source_, path, expected + ", got " + describeJson(v));
}

int64_t JsonObjectReader::integer(std::string_view key, const IntegerRange& range) const {
    return integerAt(value(key), pathOf(key), range);
}

uint64_t JsonObjectReader::unsignedInteger(std::string_view key) const {
    const json& v = value(key);
    const std::string path = pathOf(key);
    const char* allowed = "[0, 18446744073709551615]";
    if (v.is_number_unsigned()) return v.get<uint64_t>();
    if (v.is_number_integer()) {
        const int64_t x = v.get<int64_t>();
        if (x < 0) throwJsonOutOfRange(source_, path, std::to_string(x), allowed);
        return static_cast<uint64_t>(x);
    }
    if (v.is_number_float() && integers_ == JsonIntegers::WholeNumbers) {
        const double x = v.get<double>();
        if (std::isfinite(x) && x == std::floor(x)) {
            if (x < 0 || x >= 0x1p64) throwJsonOutOfRange(source_, path, formatNumber(x), allowed);
            return static_cast<uint64_t>(x);
        }
    }
    const std::string got = v.is_number_float() ? formatNumber(v.get<double>()) : describeJson(v);
    throwJsonError(source_, path,
                   std::string("expected an integer in ") + allowed + ", got " + got);
}

bool JsonObjectReader::boolean(std::string_view key) const {
    const json& v = value(key);
    if (!v.is_boolean()) fail(key, "expected true or false, got " + describeJson(v));
    return v.get<bool>();
}

std::string JsonObjectReader::string(std::string_view key) const {
    const json& v = value(key);
    if (!v.is_string()) fail(key, "expected a string, got " + describeJson(v));
    return v.get<std::string>();
}

size_t JsonObjectReader::oneOf(std::string_view key,
                               std::initializer_list<std::string_view> allowed) const {
    return oneOf(key, std::span<const std::string_view>(allowed.begin(), allowed.size()));
}

size_t JsonObjectReader::oneOf(std::string_view key,
                               std::span<const std::string_view> allowed) const {
    const json& v = value(key);
    if (v.is_string()) {
        const std::string& s = v.get_ref<const std::string&>();
        for (size_t i = 0; i < allowed.size(); ++i)
            if (s == allowed[i]) return i;
    }
    fail(key, std::string(allowed.size() == 1 ? "expected " : "expected one of ") +
                  joined(allowed, true) + ", got " + describeJson(v));
}

std::vector<double> JsonObjectReader::numbers(std::string_view key, size_t count,
                                              const NumberRange& range,
                                              std::string_view what) const {
    const json& v = value(key);
    if (!v.is_array() || v.size() != count)
        fail(key, "expected an array of " + counted(count, "number") + spaced(range.expectation()) +
                      spaced(what) + ", got " + describeJson(v));
    const std::string path = pathOf(key);
    std::vector<double> out;
    out.reserve(count);
    for (size_t k = 0; k < count; ++k)
        out.push_back(readJsonNumber(v[k], source_, jsonIndexPath(path, k), range));
    return out;
}

std::vector<int64_t> JsonObjectReader::integers(std::string_view key, size_t minCount,
                                                size_t maxCount, const IntegerRange& range,
                                                std::string_view what) const {
    const json& v = value(key);
    if (!v.is_array() || v.size() < minCount || v.size() > maxCount) {
        const std::string count =
            minCount == maxCount ? counted(minCount, "integer")
                                 : std::to_string(minCount) + " to " + counted(maxCount, "integer");
        fail(key, "expected an array of " + count +
                      (range.any() ? std::string() : " in " + range.text()) + spaced(what) +
                      ", got " + describeJson(v));
    }
    const std::string path = pathOf(key);
    std::vector<int64_t> out;
    out.reserve(v.size());
    for (size_t k = 0; k < v.size(); ++k)
        out.push_back(integerAt(v[k], jsonIndexPath(path, k), range));
    return out;
}

JsonObjectReader JsonObjectReader::object(std::string_view key) const {
    return JsonObjectReader(value(key), source_, pathOf(key), integers_);
}

JsonObjectReader JsonObjectReader::object(std::string_view key,
                                          std::initializer_list<std::string_view> allowed) const {
    JsonObjectReader child = object(key);
    child.allowKeys(allowed);
    return child;
}

std::vector<JsonObjectReader> JsonObjectReader::objects(std::string_view key) const {
    const json& v = value(key);
    if (!v.is_array()) fail(key, "expected an array of objects, got " + describeJson(v));
    const std::string path = pathOf(key);
    std::vector<JsonObjectReader> out;
    out.reserve(v.size());
    for (size_t i = 0; i < v.size(); ++i)
        out.emplace_back(v[i], source_, jsonIndexPath(path, i), integers_);
    return out;
}

}  // namespace weft
