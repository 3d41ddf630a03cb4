// weft/core/text_parse.h — tokenising text inputs: line-based files (curve
// files) and small flag values (parseColour).
//
// Shared by the curve readers of core/curves.cpp and the vertex colour reader
// of render/curves.cpp. Whitespace is ' ', '\t', '\r', '\n', '\f', '\v'.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/rgb.h"

namespace weft {

inline bool isTextSpace(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

inline std::string_view trim(std::string_view s) {
    size_t b = 0, e = s.size();
    while (b < e && isTextSpace(s[b])) ++b;
    while (e > b && isTextSpace(s[e - 1])) --e;
    return s.substr(b, e - b);
}

inline std::vector<std::string_view> splitWhitespace(std::string_view s) {
    std::vector<std::string_view> tokens;
    size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && isTextSpace(s[i])) ++i;
        const size_t start = i;
        while (i < s.size() && !isTextSpace(s[i])) ++i;
        if (i > start) tokens.push_back(s.substr(start, i - start));
    }
    return tokens;
}

// The whole token as a number; a leading '+' is accepted, and for doubles so
// are "nan" and "inf" (callers reject them with a clearer message).
template <typename Number>
bool parseNumber(std::string_view tok, Number* v) {
    if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
    if (tok.empty()) return false;
    const auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), *v);
    return ec == std::errc() && end == tok.data() + tok.size();
}

// The bytes of `s` with non-printable ones as \xNN, cut after maxLength, for messages.
inline std::string printable(std::string_view s, size_t maxLength = 60) {
    std::string out;
    for (char c : s.substr(0, maxLength)) {
        const auto u = static_cast<unsigned char>(c);
        if (u >= 0x20 && u < 0x7f) {
            out += c;
        } else {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", u);
            out += buf;
        }
    }
    if (s.size() > maxLength) out += "...";
    return out;
}

// Calls f(lineNumber, line) for every line (1-based, without "\n" or a final "\r").
template <typename F>
void forEachLine(std::string_view text, F&& f) {
    size_t lineNo = 0, pos = 0;
    while (pos < text.size()) {
        size_t end = text.find('\n', pos);
        if (end == std::string_view::npos) end = text.size();
        std::string_view line = text.substr(pos, end - pos);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        f(++lineNo, line);
        pos = end + 1;
    }
}

// "R,G,B" with each value in [0, 1] (a colour flag such as --c-tt);
// InputError naming `flag` otherwise.
inline Rgb parseColour(const std::string& text, const std::string& flag) {
    const auto fail = [&] {
        return InputError(flag + ": expected R,G,B with each value in [0, 1], got \"" +
                          printable(text) + "\"");
    };
    Rgb colour;
    size_t start = 0;
    for (int c = 0; c < 3; ++c) {
        const size_t comma = text.find(',', start);
        if ((c < 2) == (comma == std::string::npos)) throw fail();
        const std::string_view token =
            trim(std::string_view(text).substr(start, c < 2 ? comma - start : std::string::npos));
        double v;
        if (!parseNumber(token, &v) || !std::isfinite(v) || v < 0 || v > 1) throw fail();
        colour[c] = v;
        start = comma + 1;
    }
    return colour;
}

// "#rrggbb" (hexadecimal digits, either case) as its three bytes / 255; none
// for any other text. The sRGB colours of a scene's and weft yarn appearance's
// "appearance".
inline std::optional<Rgb> parseHexColour(std::string_view text) {
    if (text.size() != 7 || text[0] != '#') return std::nullopt;
    Rgb colour;
    for (int c = 0; c < 3; ++c) {
        int byte = 0;
        for (int k = 1; k <= 2; ++k) {
            const char d = text[2 * c + k];
            const int v = d >= '0' && d <= '9'   ? d - '0'
                          : d >= 'a' && d <= 'f' ? d - 'a' + 10
                          : d >= 'A' && d <= 'F' ? d - 'A' + 10
                                                 : -1;
            if (v < 0) return std::nullopt;
            byte = 16 * byte + v;
        }
        colour[c] = byte / 255.0;
    }
    return colour;
}

// An sRGB colour flag: "#rrggbb" or "R,G,B" in [0, 1]; InputError naming `flag`.
inline Rgb parseSrgbColour(const std::string& text, const std::string& flag) {
    if (const std::optional<Rgb> hex = parseHexColour(text)) return *hex;
    if (!text.empty() && text[0] == '#')
        throw InputError(flag + ": expected #rrggbb or R,G,B in [0, 1], got \"" + printable(text) +
                         "\"");
    return parseColour(text, flag);
}

}  // namespace weft
