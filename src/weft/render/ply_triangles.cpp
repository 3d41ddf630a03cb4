// The PLY mesh reader of scene_objects.h: Greg Turk's polygon file format
// (http://paulbourke.net/dataformats/ply/), as Mitsuba, Blender and MeshLab
// write it. The header declares elements in order, each with a count and its
// properties (scalars, or lists with a count type and an item type); the body
// holds every instance of every element in that order, as text ("ascii") or
// as bytes ("binary_little_endian", "binary_big_endian"). weft keeps the
// vertex element's x, y, z and the face element's vertex_indices (or
// vertex_index) and reads past everything else: normals, colours, texture
// coordinates, other elements.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/json_message.h"
#include "weft/core/text_parse.h"
#include "weft/render/scene_limits.h"
#include "weft/render/scene_objects.h"

namespace weft::render {

namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

struct PlyTypeName {
    const char* name;
    PlyType type;
};
// Both spellings of the format's specification.
constexpr PlyTypeName kPlyTypes[] = {
    {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
    {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
    {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
    {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
    {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
    {"float64", PlyType::Float64}};

std::optional<PlyType> plyType(std::string_view name) {
    for (const PlyTypeName& t : kPlyTypes)
        if (name == t.name) return t.type;
    return std::nullopt;
}

size_t plyTypeSize(PlyType t) {
    switch (t) {
        case PlyType::Int8:
        case PlyType::UInt8:
            return 1;
        case PlyType::Int16:
        case PlyType::UInt16:
            return 2;
        case PlyType::Int32:
        case PlyType::UInt32:
        case PlyType::Float32:
            return 4;
        case PlyType::Float64:
            return 8;
    }
    return 8;
}

bool isIntegerType(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct PlyProperty {
    std::string name;
    bool list = false;
    PlyType countType = PlyType::UInt8;  // lists
    PlyType type = PlyType::Float32;     // the value, or a list's items
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct PlyHeader {
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElement> elements;
    size_t bodyOffset = 0;  // the byte after "end_header\n"
    size_t bodyLine = 0;    // the body's first line (ascii messages)
};

PlyHeader readPlyHeader(std::string_view bytes, const std::string& path) {
    PlyHeader h;
    size_t pos = 0, lineNo = 0;
    bool sawFormat = false;
    for (;;) {
        const size_t end = bytes.find('\n', pos);
        if (end == std::string_view::npos)
            throw InputError(path + ": the PLY header has no end_header line");
        std::string_view line = bytes.substr(pos, end - pos);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos = end + 1;
        ++lineNo;
        const auto fail = [&](const std::string& what) {
            throw InputError(path + ":" + std::to_string(lineNo) + ": " + what);
        };
        const std::vector<std::string_view> tok = splitWhitespace(line);
        if (lineNo == 1) {
            if (tok.size() != 1 || tok[0] != "ply")
                fail("not a PLY file: it must start with a line \"ply\", got '" + printable(line) +
                     "'");
            continue;
        }
        if (tok.empty() || tok[0] == "comment" || tok[0] == "obj_info") continue;
        if (tok[0] == "format") {
            if (tok.size() != 3 || tok[2] != "1.0")
                fail("expected 'format ascii|binary_little_endian|binary_big_endian 1.0', got '" +
                     printable(line) + "'");
            if (tok[1] == "ascii")
                h.format = PlyFormat::Ascii;
            else if (tok[1] == "binary_little_endian")
                h.format = PlyFormat::BinaryLittleEndian;
            else if (tok[1] == "binary_big_endian")
                h.format = PlyFormat::BinaryBigEndian;
            else
                fail("format \"" + printable(tok[1]) +
                     "\" (allowed: ascii, binary_little_endian, binary_big_endian)");
            sawFormat = true;
        } else if (tok[0] == "element") {
            PlyElement e;
            if (tok.size() != 3 || !parseNumber(tok[2], &e.count))
                fail("expected 'element NAME COUNT', got '" + printable(line) + "'");
            e.name = std::string(tok[1]);
            h.elements.push_back(std::move(e));
        } else if (tok[0] == "property") {
            if (h.elements.empty()) fail("a property before any element");
            PlyProperty p;
            const auto typeOf = [&](std::string_view name) {
                const std::optional<PlyType> t = plyType(name);
                if (!t)
                    fail("property type \"" + printable(name) +
                         "\" (allowed: char, uchar, short, ushort, int, uint, float, double, or "
                         "int8 ... float64)");
                return *t;
            };
            if (tok.size() == 5 && tok[1] == "list") {
                p.list = true;
                p.countType = typeOf(tok[2]);
                if (!isIntegerType(p.countType))
                    fail("a list's count type must be an integer type, not " + std::string(tok[2]));
                p.type = typeOf(tok[3]);
                p.name = std::string(tok[4]);
            } else if (tok.size() == 3) {
                p.type = typeOf(tok[1]);
                p.name = std::string(tok[2]);
            } else {
                fail(
                    "expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME', got '" +
                    printable(line) + "'");
            }
            h.elements.back().properties.push_back(std::move(p));
        } else if (tok[0] == "end_header") {
            if (tok.size() != 1) fail("expected 'end_header', got '" + printable(line) + "'");
            break;
        } else {
            fail("unknown header line '" + printable(line) +
                 "' (allowed: format, comment, obj_info, element, property, end_header)");
        }
    }
    if (!sawFormat) throw InputError(path + ": the PLY header has no format line");
    h.bodyOffset = pos;
    h.bodyLine = lineNo + 1;
    return h;
}

// Where a value is, for messages ("element face 12.vertex_indices"), made
// only when one is needed.
struct PlyPlace {
    const PlyElement& element;
    uint64_t instance;
    const PlyProperty* property = nullptr;
    const char* suffix = "";

    std::string str() const {
        return "element " + printable(element.name) + " " + std::to_string(instance) +
               (property ? "." + printable(property->name) : std::string()) + suffix;
    }
};

// The body's values one at a time, as doubles (every PLY integer fits one exactly).
class PlyBody {
  public:
    PlyBody(std::string_view bytes, const PlyHeader& h, const std::string& path)
        : bytes_(bytes), pos_(h.bodyOffset), line_(h.bodyLine), format_(h.format), path_(path) {}

    double next(PlyType type, const PlyPlace& where) {
        return format_ == PlyFormat::Ascii ? nextText(type, where) : nextBinary(type, where);
    }

  private:
    double nextText(PlyType type, const PlyPlace& where) {
        while (pos_ < bytes_.size() && isTextSpace(bytes_[pos_])) {
            if (bytes_[pos_] == '\n') ++line_;
            ++pos_;
        }
        const size_t start = pos_;
        while (pos_ < bytes_.size() && !isTextSpace(bytes_[pos_])) ++pos_;
        const std::string_view token = bytes_.substr(start, pos_ - start);
        const auto at = [&] { return path_ + ":" + std::to_string(line_) + ": " + where.str(); };
        if (token.empty()) throw InputError(at() + ": the file ends before it");
        if (isIntegerType(type)) {
            long long v = 0;
            if (!parseNumber(token, &v))
                throw InputError(at() + ": expected an integer, got '" + printable(token) + "'");
            return static_cast<double>(v);
        }
        double v = 0;
        if (!parseNumber(token, &v))
            throw InputError(at() + ": expected a number, got '" + printable(token) + "'");
        return v;
    }

    double nextBinary(PlyType type, const PlyPlace& where) {
        const size_t size = plyTypeSize(type);
        if (bytes_.size() - pos_ < size)
            throw InputError(path_ + ": " + where.str() + ": the file ends before it (byte " +
                             std::to_string(pos_) + " of " + std::to_string(bytes_.size()) + ")");
        unsigned char b[8];
        std::memcpy(b, bytes_.data() + pos_, size);
        pos_ += size;
        const bool swap =
            (format_ == PlyFormat::BinaryBigEndian) == (std::endian::native == std::endian::little);
        if (swap) std::reverse(b, b + size);
        switch (type) {
            case PlyType::Int8:
                return static_cast<double>(std::bit_cast<int8_t>(b[0]));
            case PlyType::UInt8:
                return b[0];
            case PlyType::Int16:
                return static_cast<double>(load<int16_t>(b));
            case PlyType::UInt16:
                return static_cast<double>(load<uint16_t>(b));
            case PlyType::Int32:
                return static_cast<double>(load<int32_t>(b));
            case PlyType::UInt32:
                return static_cast<double>(load<uint32_t>(b));
            case PlyType::Float32:
                return static_cast<double>(load<float>(b));
            case PlyType::Float64:
                return load<double>(b);
        }
        return 0;
    }

    template <typename T>
    static T load(const unsigned char* b) {
        T v;
        std::memcpy(&v, b, sizeof v);
        return v;
    }

    std::string_view bytes_;
    size_t pos_;
    size_t line_;
    PlyFormat format_;
    const std::string& path_;
};

}  // namespace

Triangles parsePlyTriangles(std::string_view bytes, const std::string& path) {
    const PlyHeader header = readPlyHeader(bytes, path);
    PlyBody body(bytes, header, path);
    Triangles t;
    bool sawVertices = false, sawFaces = false;
    std::vector<uint32_t> face;
    for (const PlyElement& e : header.elements) {
        const bool vertex = e.name == "vertex", faces = e.name == "face";
        int xyz[3] = {-1, -1, -1};
        int indices = -1;
        for (size_t k = 0; k < e.properties.size(); ++k) {
            const PlyProperty& p = e.properties[k];
            if (vertex && !p.list) {
                if (p.name == "x") xyz[0] = static_cast<int>(k);
                if (p.name == "y") xyz[1] = static_cast<int>(k);
                if (p.name == "z") xyz[2] = static_cast<int>(k);
            }
            if (faces && p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
                if (!isIntegerType(p.type))
                    throw InputError(path + ": the face element's " + p.name +
                                     " must hold integers");
                indices = static_cast<int>(k);
            }
        }
        if (vertex) {
            for (int c = 0; c < 3; ++c)
                if (xyz[c] < 0)
                    throw InputError(path + ": the vertex element has no property " +
                                     std::string(1, "xyz"[c]));
            if (e.count > std::numeric_limits<uint32_t>::max())
                throw InputError(path + ": " + std::to_string(e.count) +
                                 " vertices: allowed at most 4294967295");
            sawVertices = true;
        }
        if (faces) {
            if (indices < 0)
                throw InputError(path + ": the face element has no list property vertex_indices");
            sawFaces = true;
        }
        // An element without properties has no bytes: nothing to read, however many.
        const uint64_t instances = e.properties.empty() ? 0 : e.count;
        for (uint64_t i = 0; i < instances; ++i) {
            double p[3] = {0, 0, 0};
            for (size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& prop = e.properties[k];
                const PlyPlace where{e, i, &prop};
                if (!prop.list) {
                    const double v = body.next(prop.type, where);
                    for (int c = 0; c < 3; ++c)
                        if (vertex && xyz[c] == static_cast<int>(k)) p[c] = v;
                    continue;
                }
                const double n = body.next(prop.countType, {e, i, &prop, " count"});
                if (n < 0)
                    throw InputError(path + ": " + where.str() + ": count " + formatNumber(n) +
                                     " is negative");
                const bool keep = faces && indices == static_cast<int>(k);
                if (keep) face.clear();
                for (uint64_t j = 0; j < static_cast<uint64_t>(n); ++j) {
                    const double v = body.next(prop.type, where);
                    if (!keep) continue;
                    if (v < 0 || v > std::numeric_limits<uint32_t>::max())
                        throw InputError(path + ": " + where.str() + ": vertex index " +
                                         formatNumber(v) + " is out of range");
                    face.push_back(static_cast<uint32_t>(v));
                }
                if (!keep) continue;
                if (face.size() < 3)
                    throw InputError(path + ": " + where.str() +
                                     ": a face needs at least 3 vertices, got " +
                                     std::to_string(face.size()));
                for (size_t k2 = 1; k2 + 1 < face.size(); ++k2) {
                    if (static_cast<int64_t>(t.indices.size()) >= kMaxSceneTriangles)
                        throw InputError(path + ": more than " +
                                         std::to_string(kMaxSceneTriangles) +
                                         " triangles: the most a scene takes");
                    t.indices.push_back({face[0], face[k2], face[k2 + 1]});
                }
            }
            if (vertex) {
                for (double v : p)
                    if (!std::isfinite(v) || std::abs(v) > kMaxSceneCoordinate)
                        throw InputError(path + ": " + PlyPlace{e, i}.str() +
                                         ": vertex coordinate out of range: allowed finite, "
                                         "within +-" +
                                         formatNumber(kMaxSceneCoordinate));
                t.vertices.push_back({p[0], p[1], p[2]});
            }
        }
    }
    if (!sawVertices) throw InputError(path + ": no vertex element");
    if (!sawFaces || t.indices.empty())
        throw InputError(path + ": no faces (a face element with vertex_indices): nothing to draw");
    // Faces may come before the vertices: their indices are checked at the end.
    for (const auto& tri : t.indices)
        for (uint32_t v : tri)
            if (v >= t.vertices.size())
                throw InputError(path + ": vertex index " + std::to_string(v) +
                                 " is out of range: " + std::to_string(t.vertices.size()) +
                                 " vertices");
    return t;
}

}  // namespace weft::render
