#include "weft/core/npy.h"

#include <bit>
#include <cstdio>
#include <cstring>
#include <limits>

#include "weft/core/error.h"
#include "weft/core/file.h"

namespace weft {

static_assert(std::endian::native == std::endian::little,
              "the .npy reader and writer assume a little-endian host");

namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr size_t kMagicLen = 6;
constexpr size_t kArrayAlign = 64;           // numpy.lib.format.ARRAY_ALIGN
constexpr size_t kGrowthAxisMaxDigits = 21;  // numpy.lib.format.GROWTH_AXIS_MAX_DIGITS
constexpr const char* kSupportedDescrs = "<f4 <f8 <i4 <i8 |u1 |b1";

// Item size of a supported canonical descr, 0 if unsupported.
size_t descrItemSize(std::string_view d) {
    if (d == "<f8" || d == "<i8") return 8;
    if (d == "<f4" || d == "<i4") return 4;
    if (d == "|u1" || d == "|b1") return 1;
    return 0;
}

// Maps the spellings numpy may use to the canonical one; "" if unsupported.
std::string canonicalDescr(std::string_view d) {
    if (d == "<u1" || d == "|u1") return "|u1";
    if (descrItemSize(d) != 0) return std::string(d);
    return "";
}

std::string quoteForMessage(std::string_view s) {
    std::string out = "'";
    for (char c : s) {
        if (c == '\n') {
            out += "\\n";
        } else if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", static_cast<unsigned char>(c));
            out += buf;
        } else {
            out += c;
        }
    }
    return out + "'";
}

// Parser for the header: the repr of a Python dict with the keys 'descr'
// (str), 'fortran_order' (bool) and 'shape' (tuple of int), in any order.
class HeaderParser {
public:
    HeaderParser(std::string_view text, const std::string& path) : s_(text), path_(path) {}

    void parse(std::string* descr, bool* fortranOrder, std::vector<size_t>* shape) {
        bool haveDescr = false, haveFortran = false, haveShape = false;
        skipSpace();
        expect('{');
        for (;;) {
            skipSpace();
            if (peek() == '}') break;
            const size_t keyPos = pos_;
            const std::string key = parseString();
            skipSpace();
            expect(':');
            skipSpace();
            if (key == "descr") {
                if (haveDescr) fail("duplicate key 'descr'", keyPos);
                if (peek() != '\'' && peek() != '"')
                    fail(
                        "'descr' must be a dtype string such as '<f8' (structured dtypes are "
                        "not supported)",
                        pos_);
                *descr = parseString();
                haveDescr = true;
            } else if (key == "fortran_order") {
                if (haveFortran) fail("duplicate key 'fortran_order'", keyPos);
                *fortranOrder = parseBool();
                haveFortran = true;
            } else if (key == "shape") {
                if (haveShape) fail("duplicate key 'shape'", keyPos);
                *shape = parseShape();
                haveShape = true;
            } else {
                fail("unexpected key " + quoteForMessage(key) +
                         " (allowed: 'descr', 'fortran_order', 'shape')",
                     keyPos);
            }
            skipSpace();
            if (peek() == ',') {
                ++pos_;
                continue;
            }
            if (peek() != '}') fail("expected ',' or '}'", pos_);
        }
        ++pos_;  // '}'
        skipSpace();
        if (pos_ != s_.size()) fail("unexpected text after the closing '}'", pos_);
        if (!haveDescr) fail("missing key 'descr'", pos_);
        if (!haveFortran) fail("missing key 'fortran_order'", pos_);
        if (!haveShape) fail("missing key 'shape'", pos_);
    }

private:
    [[noreturn]] void fail(const std::string& what, size_t at) const {
        throw InputError(path_ + ": malformed .npy header: " + what + " at offset " +
                         std::to_string(at) + " of " + quoteForMessage(s_));
    }
    char peek() const { return pos_ < s_.size() ? s_[pos_] : '\0'; }
    void skipSpace() {
        while (pos_ < s_.size() &&
               (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\n' || s_[pos_] == '\r'))
            ++pos_;
    }
    void expect(char c) {
        if (peek() != c) fail(std::string("expected '") + c + "'", pos_);
        ++pos_;
    }
    std::string parseString() {
        const char quote = peek();
        if (quote != '\'' && quote != '"') fail("expected a quoted string", pos_);
        const size_t start = ++pos_;
        while (pos_ < s_.size() && s_[pos_] != quote) {
            if (s_[pos_] == '\\') fail("escape sequences are not supported", pos_);
            ++pos_;
        }
        if (pos_ >= s_.size()) fail("unterminated string", start - 1);
        return std::string(s_.substr(start, pos_++ - start));
    }
    bool parseBool() {
        if (s_.substr(pos_, 4) == "True") {
            pos_ += 4;
            return true;
        }
        if (s_.substr(pos_, 5) == "False") {
            pos_ += 5;
            return false;
        }
        fail("'fortran_order' must be True or False", pos_);
    }
    size_t parseInt() {
        const size_t start = pos_;
        size_t v = 0;
        while (pos_ < s_.size() && s_[pos_] >= '0' && s_[pos_] <= '9') {
            const size_t digit = static_cast<size_t>(s_[pos_] - '0');
            if (v > (std::numeric_limits<size_t>::max() - digit) / 10)
                fail("shape dimension too large", start);
            v = v * 10 + digit;
            ++pos_;
        }
        if (pos_ == start) fail("expected a non-negative integer in 'shape'", pos_);
        if (peek() == 'L') ++pos_;  // Python 2 long literal, as old numpy wrote.
        return v;
    }
    std::vector<size_t> parseShape() {
        std::vector<size_t> dims;
        expect('(');
        skipSpace();
        while (peek() != ')') {
            dims.push_back(parseInt());
            skipSpace();
            if (peek() == ',') {
                ++pos_;
                skipSpace();
            } else if (peek() != ')') {
                fail("expected ',' or ')' in 'shape'", pos_);
            }
        }
        ++pos_;  // ')'
        return dims;
    }

    std::string_view s_;
    const std::string& path_;
    size_t pos_ = 0;
};

// Element count and byte count for shape/descr; InputError on overflow.
size_t checkedByteCount(const std::vector<size_t>& shape, size_t itemSize,
                        const std::string& path) {
    size_t n = itemSize;
    for (size_t d : shape) {
        if (d != 0 && n > std::numeric_limits<size_t>::max() / d)
            throw InputError(path + ": shape " + npyShapeString(shape) + " is too large");
        n *= d;
    }
    return n;
}

uint32_t readLE(std::string_view b, size_t offset, size_t width) {
    uint32_t v = 0;
    for (size_t i = 0; i < width; ++i)
        v |= static_cast<uint32_t>(static_cast<unsigned char>(b[offset + i])) << (8 * i);
    return v;
}

template <typename T>
constexpr const char* descrOf();
template <>
constexpr const char* descrOf<float>() {
    return "<f4";
}
template <>
constexpr const char* descrOf<double>() {
    return "<f8";
}
template <>
constexpr const char* descrOf<int32_t>() {
    return "<i4";
}
template <>
constexpr const char* descrOf<int64_t>() {
    return "<i8";
}
template <>
constexpr const char* descrOf<uint8_t>() {
    return "|u1";
}

template <typename T>
void appendAsDoubles(const std::vector<unsigned char>& bytes, std::vector<double>* out) {
    const size_t n = bytes.size() / sizeof(T);
    out->resize(n);
    for (size_t i = 0; i < n; ++i) {
        T v;
        std::memcpy(&v, bytes.data() + i * sizeof(T), sizeof(T));
        (*out)[i] = static_cast<double>(v);
    }
}

}  // namespace

size_t NpyArray::size() const {
    size_t n = 1;
    for (size_t d : shape) n *= d;
    return n;
}

size_t NpyArray::itemSize() const { return descrItemSize(descr); }

std::string npyShapeString(const std::vector<size_t>& shape) {
    std::string s = "(";
    for (size_t i = 0; i < shape.size(); ++i) {
        if (i > 0) s += ", ";
        s += std::to_string(shape[i]);
    }
    if (shape.size() == 1) s += ",";
    return s + ")";
}

NpyArray decodeNpy(std::string_view bytes, const std::string& path) {
    if (bytes.size() < kMagicLen || std::memcmp(bytes.data(), kMagic, kMagicLen) != 0)
        throw InputError(path + ": not a .npy file (bad magic; expected \\x93NUMPY)");
    if (bytes.size() < kMagicLen + 2)
        throw InputError(path + ": truncated .npy file: it ends inside the version");
    const int major = static_cast<unsigned char>(bytes[6]);
    const int minor = static_cast<unsigned char>(bytes[7]);
    if (minor != 0 || major < 1 || major > 3)
        throw InputError(path + ": unsupported .npy format version " + std::to_string(major) + "." +
                         std::to_string(minor) + " (supported: 1.0, 2.0, 3.0)");
    const size_t lenWidth = major == 1 ? 2 : 4;
    const size_t headerStart = kMagicLen + 2 + lenWidth;
    if (bytes.size() < headerStart)
        throw InputError(path + ": truncated .npy file: it ends inside the header length");
    const size_t headerLen = readLE(bytes, kMagicLen + 2, lenWidth);
    if (bytes.size() - headerStart < headerLen)
        throw InputError(path + ": truncated .npy file: the header declares " +
                         std::to_string(headerLen) + " bytes but the file has " +
                         std::to_string(bytes.size() - headerStart) + " after the prefix");
    const std::string_view header = bytes.substr(headerStart, headerLen);

    std::string descr;
    bool fortranOrder = false;
    NpyArray array;
    HeaderParser(header, path).parse(&descr, &fortranOrder, &array.shape);

    if (fortranOrder)
        throw InputError(path +
                         ": fortran_order True is not supported; save a C-order array "
                         "(numpy.ascontiguousarray)");
    if (!descr.empty() && descr[0] == '>')
        throw InputError(path + ": big-endian dtype '" + descr +
                         "' is not supported; convert with arr.astype('<" + descr.substr(1) +
                         "') (supported: " + kSupportedDescrs + ")");
    array.descr = canonicalDescr(descr);
    if (array.descr.empty())
        throw InputError(path + ": unsupported dtype '" + descr +
                         "' (supported: " + kSupportedDescrs + ")");

    const size_t dataBytes = checkedByteCount(array.shape, array.itemSize(), path);
    const size_t have = bytes.size() - headerStart - headerLen;
    if (have < dataBytes)
        throw InputError(path + ": truncated: shape " + npyShapeString(array.shape) + " of " +
                         array.descr + " needs " + std::to_string(dataBytes) +
                         " data bytes but the file has " + std::to_string(have));
    if (have > dataBytes)
        throw InputError(path + ": " + std::to_string(have - dataBytes) +
                         " unexpected bytes after the data of shape " +
                         npyShapeString(array.shape) + " " + array.descr);
    const auto* data =
        reinterpret_cast<const unsigned char*>(bytes.data()) + headerStart + headerLen;
    array.bytes.assign(data, data + dataBytes);
    return array;
}

NpyArray readNpy(const std::string& path) { return decodeNpy(readFile(path), path); }

std::vector<double> npyToDoubles(const NpyArray& array, const std::string& path) {
    const size_t itemSize = array.itemSize();
    if (itemSize == 0)
        throw InputError(path + ": unsupported dtype '" + array.descr +
                         "' (supported: " + kSupportedDescrs + ")");
    if (array.bytes.size() != checkedByteCount(array.shape, itemSize, path))
        throw InputError(path + ": " + std::to_string(array.bytes.size()) +
                         " data bytes do not match shape " + npyShapeString(array.shape) + " of " +
                         array.descr);
    std::vector<double> out;
    const std::string& d = array.descr;
    if (d == "<f8") {
        appendAsDoubles<double>(array.bytes, &out);
    } else if (d == "<f4") {
        appendAsDoubles<float>(array.bytes, &out);
    } else if (d == "<i8") {
        appendAsDoubles<int64_t>(array.bytes, &out);
    } else if (d == "<i4") {
        appendAsDoubles<int32_t>(array.bytes, &out);
    } else if (d == "|u1") {
        appendAsDoubles<uint8_t>(array.bytes, &out);
    } else {  // "|b1": numpy bools are 0 or 1; treat any non-zero byte as true.
        out.resize(array.bytes.size());
        for (size_t i = 0; i < out.size(); ++i) out[i] = array.bytes[i] != 0 ? 1.0 : 0.0;
    }
    return out;
}

template <typename T>
std::string encodeNpy(const T* data, const std::vector<size_t>& shape) {
    // numpy.lib.format._write_array_header: the repr of a dict with sorted
    // keys, then spare spaces so the first axis can grow in place ...
    std::string dict = std::string("{'descr': '") + descrOf<T>() +
                       "', 'fortran_order': False, 'shape': " + npyShapeString(shape) + ", }";
    if (!shape.empty()) {
        const size_t digits = std::to_string(shape[0]).size();
        dict.append(kGrowthAxisMaxDigits > digits ? kGrowthAxisMaxDigits - digits : 0, ' ');
    }
    // ... then _wrap_header: pad with spaces and a final '\n' so the data
    // starts on a 64-byte boundary (a full 64 bytes of padding if already
    // aligned, as numpy does).
    size_t lenWidth = 2;
    size_t hlen = dict.size() + 1;
    size_t padLen = kArrayAlign - (kMagicLen + 2 + lenWidth + hlen) % kArrayAlign;
    int major = 1;
    if (hlen + padLen > 0xffff) {
        major = 2;
        lenWidth = 4;
        padLen = kArrayAlign - (kMagicLen + 2 + lenWidth + hlen) % kArrayAlign;
    }
    const size_t totalHeader = hlen + padLen;
    const size_t dataBytes = checkedByteCount(shape, sizeof(T), "encodeNpy");

    std::string out;
    out.reserve(kMagicLen + 2 + lenWidth + totalHeader + dataBytes);
    out.append(kMagic, kMagicLen);
    out += static_cast<char>(major);
    out += '\0';
    for (size_t i = 0; i < lenWidth; ++i) out += static_cast<char>((totalHeader >> (8 * i)) & 0xff);
    out += dict;
    out.append(padLen, ' ');
    out += '\n';
    if (dataBytes > 0) out.append(reinterpret_cast<const char*>(data), dataBytes);
    return out;
}

template <typename T>
void writeNpy(const std::string& path, const T* data, const std::vector<size_t>& shape) {
    writeFileAtomic(path, encodeNpy(data, shape));
}

#define WEFT_INSTANTIATE_NPY(T)                                              \
    template std::string encodeNpy<T>(const T*, const std::vector<size_t>&); \
    template void writeNpy<T>(const std::string&, const T*, const std::vector<size_t>&);
WEFT_INSTANTIATE_NPY(float)
WEFT_INSTANTIATE_NPY(double)
WEFT_INSTANTIATE_NPY(int32_t)
WEFT_INSTANTIATE_NPY(int64_t)
WEFT_INSTANTIATE_NPY(uint8_t)
#undef WEFT_INSTANTIATE_NPY

NpyMatrix readNpyMatrix(const std::string& path, size_t cols, const std::string& what) {
    NpyArray array = readNpy(path);
    if ((array.descr != "<f4" && array.descr != "<f8") || array.shape.size() != 2 ||
        array.shape[1] != cols)
        throw InputError(path + ": expected a float32 or float64 array of shape (n, " +
                         std::to_string(cols) + ")" + (what.empty() ? "" : " for " + what) +
                         ", got " + array.descr + " " + npyShapeString(array.shape));
    NpyMatrix m;
    m.rows = array.shape[0];
    m.cols = cols;
    m.values = npyToDoubles(array, path);
    return m;
}

}  // namespace weft
