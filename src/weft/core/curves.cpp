#include "weft/core/curves.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/text_parse.h"

namespace weft {

static_assert(std::endian::native == std::endian::little,
              "the BCC reader and writer assume a little-endian host (BCC is little-endian)");

namespace {

// BCC layout (Yuksel, cyCodeBase "Using BCC files"): a 64-byte header, then per
// curve an int32 point count (negative: closed) and count float32 xyz triples.
constexpr size_t kBccHeaderSize = 64;
constexpr size_t kBccOffsetBytesPerValue = 3;
constexpr size_t kBccOffsetCurveType = 4;
constexpr size_t kBccOffsetDimensions = 6;
constexpr size_t kBccOffsetCurveCount = 8;
constexpr size_t kBccOffsetPointCount = 16;
constexpr size_t kBccPointSize = 12;
// The smallest valid curve: its count and 2 points. Bounds the curve count by
// the file size before anything is reserved.
constexpr size_t kBccMinCurveSize = 4 + 2 * kBccPointSize;

// Coordinates end up in float32 geometry (Embree): a finite double beyond this
// would become infinite there.
constexpr double kFloatMax = std::numeric_limits<float>::max();

template <typename T>
T loadLittleEndian(const char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

template <typename T>
void storeLittleEndian(std::string* out, T v) {
    char buf[sizeof v];
    std::memcpy(buf, &v, sizeof v);
    out->append(buf, sizeof v);
}

constexpr size_t kBccInfoSize = 40;

std::string hexByte(unsigned char b) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "0x%02x", b);
    return buf;
}

}  // namespace

size_t CurveSet::pointCount() const {
    size_t n = 0;
    for (const Curve& c : curves) n += c.points.size();
    return n;
}

void Bounds3::extend(const Vec3& p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
}

size_t segmentCount(const Curve& curve) {
    const size_t n = curve.points.size();
    if (n < 2) return 0;
    return curve.closed ? n : n - 1;
}

size_t segmentCount(const CurveSet& set) {
    size_t n = 0;
    for (const Curve& c : set.curves) n += segmentCount(c);
    return n;
}

std::vector<double> pointRows(const CurveSet& set) {
    std::vector<double> rows;
    rows.reserve(set.pointCount() * 4);
    for (size_t c = 0; c < set.curves.size(); ++c)
        for (const Vec3& p : set.curves[c].points)
            rows.insert(rows.end(), {static_cast<double>(c), p.x, p.y, p.z});
    return rows;
}

Bounds3 bounds(const CurveSet& set) {
    Bounds3 b;
    for (const Curve& c : set.curves)
        for (const Vec3& p : c.points) b.extend(p);
    return b;
}

CurveSet readCurves(const std::string& path) {
    const std::string ext = lowercaseExtension(path);
    if (ext == ".bcc") return parseBccCurves(readFile(path), path);
    if (ext == ".txt") return parseTextCurves(readFile(path), path);
    if (ext == ".obj") return parseObjCurves(readFile(path), path);
    throw InputError(path + ": unsupported curve file extension '" +
                     (ext.empty() ? std::string("(none)") : ext) + "' (allowed: .bcc, .txt, .obj)");
}

// ---------------------------------------------------------------------------
// BCC

CurveSet parseBccCurves(std::string_view bytes, const std::string& path) {
    const auto fail = [&](size_t offset, const std::string& what) {
        throw InputError(path + ": byte offset " + std::to_string(offset) + ": " + what);
    };
    const size_t size = bytes.size();
    if (size < kBccHeaderSize)
        fail(size,
             "truncated header: a BCC header is 64 bytes but the file has " + std::to_string(size));
    const char* h = bytes.data();
    if (std::string_view(h, 3) != "BCC")
        fail(0, "not a BCC file: signature '" + printable(std::string_view(h, 3)) +
                    "', expected 'BCC'");
    const auto bytesPerValue = static_cast<unsigned char>(h[kBccOffsetBytesPerValue]);
    if (bytesPerValue != 0x44)
        fail(kBccOffsetBytesPerValue,
             "unsupported bytes-per-value " + hexByte(bytesPerValue) +
                 " (only 0x44, 4-byte integer counts and 4-byte float values, is supported)");
    const std::string_view type(h + kBccOffsetCurveType, 2);
    CurveBasis basis = CurveBasis::Polyline;
    if (type == "PL") {
        basis = CurveBasis::Polyline;
    } else if (type == "C0") {
        basis = CurveBasis::CatmullRom;
    } else {
        fail(kBccOffsetCurveType, "unsupported curve type '" + printable(type) +
                                      "' (supported: 'PL' polyline, 'C0' uniform Catmull-Rom)");
    }
    const auto dimensions = static_cast<unsigned char>(h[kBccOffsetDimensions]);
    if (dimensions != 3)
        fail(kBccOffsetDimensions, "unsupported dimension count " + std::to_string(dimensions) +
                                       " (only 3 is supported)");
    // Byte 7 (up direction) is a viewing hint; the renderer's scene decides
    // orientation, so any value is accepted.
    const auto curveCount = loadLittleEndian<uint64_t>(h + kBccOffsetCurveCount);
    const auto declaredPoints = loadLittleEndian<uint64_t>(h + kBccOffsetPointCount);

    const size_t bodySize = size - kBccHeaderSize;
    if (curveCount == 0) fail(kBccOffsetCurveCount, "the header declares no curves");
    if (curveCount > bodySize / kBccMinCurveSize)
        fail(kBccOffsetCurveCount,
             "the header declares " + std::to_string(curveCount) + " curves but the " +
                 std::to_string(bodySize) + " bytes after the header hold at most " +
                 std::to_string(bodySize / kBccMinCurveSize) + " (a curve takes at least " +
                 std::to_string(kBccMinCurveSize) + " bytes)");
    // Checked here only against the file size; the exact match is checked once
    // the curves are read.
    const size_t maxPoints = (bodySize - 4 * curveCount) / kBccPointSize;
    if (declaredPoints > maxPoints)
        fail(kBccOffsetPointCount, "the header declares " + std::to_string(declaredPoints) +
                                       " control points but the file has room for at most " +
                                       std::to_string(maxPoints));

    CurveSet set;
    set.curves.resize(static_cast<size_t>(curveCount));
    size_t offset = kBccHeaderSize;
    uint64_t pointsRead = 0;
    for (size_t i = 0; i < set.curves.size(); ++i) {
        const std::string curveName = "curve " + std::to_string(i) + ": ";
        if (size - offset < 4)
            fail(offset, curveName + "truncated: the file ends inside the point count (curve " +
                             std::to_string(i) + " of " + std::to_string(curveCount) + ")");
        const auto signedCount = loadLittleEndian<int32_t>(h + offset);
        const size_t countOffset = offset;
        offset += 4;
        // |INT32_MIN| does not fit an int32; go through int64.
        const auto count = static_cast<uint64_t>(std::abs(static_cast<int64_t>(signedCount)));
        if (count < 2)
            fail(countOffset, curveName + "point count " + std::to_string(signedCount) +
                                  " (a curve needs at least 2 points; negative means closed)");
        const size_t room = (size - offset) / kBccPointSize;
        if (count > room)
            fail(countOffset, curveName + "truncated: the point count is " +
                                  std::to_string(signedCount) + " but the file holds at most " +
                                  std::to_string(room) + " more points");
        Curve& curve = set.curves[i];
        curve.closed = signedCount < 0;
        curve.basis = basis;
        curve.points.resize(static_cast<size_t>(count));
        for (size_t j = 0; j < count; ++j, offset += kBccPointSize) {
            float xyz[3];
            std::memcpy(xyz, h + offset, sizeof xyz);
            for (int k = 0; k < 3; ++k)
                if (!std::isfinite(xyz[k]))
                    fail(offset + 4 * static_cast<size_t>(k),
                         curveName + "point " + std::to_string(j) + " has a non-finite " +
                             "xyz"[k] + " coordinate (" + std::to_string(xyz[k]) + ")");
            curve.points[j] = Vec3(xyz[0], xyz[1], xyz[2]);
        }
        pointsRead += count;
    }
    if (offset != size)
        fail(offset, std::to_string(size - offset) + " unexpected bytes after the last of the " +
                         std::to_string(curveCount) + " curves the header declares");
    if (pointsRead != declaredPoints)
        fail(kBccOffsetPointCount, "the header declares " + std::to_string(declaredPoints) +
                                       " control points but the curves hold " +
                                       std::to_string(pointsRead));
    return set;
}

// ---------------------------------------------------------------------------
// Text polylines

CurveSet parseTextCurves(std::string_view text, const std::string& path) {
    CurveSet set;
    bool inCurve = false, nextClosed = false;
    size_t curveStartLine = 0;
    // Radii are all-or-nothing per file; the first point decides.
    size_t firstPointLine = 0;
    bool fileHasRadii = false;

    const auto finishCurve = [&] {
        if (inCurve && set.curves.back().points.size() < 2)
            throw InputError(path + ":" + std::to_string(curveStartLine) +
                             ": the curve starting here has 1 point; a curve needs at least 2 "
                             "(curves are separated by blank lines)");
        inCurve = false;
    };

    forEachLine(text, [&](size_t lineNo, std::string_view raw) {
        const auto fail = [&](const std::string& what) {
            throw InputError(path + ":" + std::to_string(lineNo) + ": " + what);
        };
        std::string_view line = trim(raw);
        if (line.empty()) {
            finishCurve();
            return;
        }
        if (line[0] == '#') {
            // "# closed" before a curve marks it closed (core formatCurveText
            // writes it, so `weft ply` output reads back unchanged).
            if (!inCurve && trim(line.substr(1)) == "closed") nextClosed = true;
            return;
        }
        line = trim(line.substr(0, line.find('#')));
        const std::vector<std::string_view> tok = splitWhitespace(line);
        double v[4];
        bool ok = tok.size() == 3 || tok.size() == 4;
        for (size_t k = 0; ok && k < tok.size(); ++k) ok = parseNumber(tok[k], &v[k]);
        if (!ok)
            fail("expected a point 'x y z' or 'x y z radius' (3 or 4 numbers), got '" +
                 printable(line) + "'");
        for (size_t k = 0; k < 3; ++k)
            if (!std::isfinite(v[k]) || std::abs(v[k]) > kFloatMax)
                fail("coordinate '" + std::string(tok[k]) +
                     "' is not a finite number in float range");
        const bool hasRadius = tok.size() == 4;
        float radius = 0;  // the renderer draws radii in float32: keep them so
        if (hasRadius) {
            radius = static_cast<float>(v[3]);
            if (!std::isfinite(radius) || !(radius > 0))
                fail("radius '" + std::string(tok[3]) +
                     "' must be a finite number > 0 (in float range)");
        }
        if (firstPointLine == 0) {
            firstPointLine = lineNo;
            fileHasRadii = hasRadius;
        } else if (hasRadius != fileHasRadii) {
            fail(std::string(hasRadius ? "point has a radius" : "point has no radius") +
                 " but the first point of the file (line " + std::to_string(firstPointLine) + ") " +
                 (fileHasRadii ? "has one" : "has none") +
                 "; give every point of the file a radius, or none");
        }
        if (!inCurve) {
            Curve& curve = set.curves.emplace_back();
            curve.closed = nextClosed;
            nextClosed = false;
            inCurve = true;
            curveStartLine = lineNo;
        }
        Curve& curve = set.curves.back();
        curve.points.emplace_back(v[0], v[1], v[2]);
        if (hasRadius) curve.radii.push_back(radius);
    });
    finishCurve();
    if (set.curves.empty()) throw InputError(path + ": no curves (no point lines)");
    return set;
}

// ---------------------------------------------------------------------------
// OBJ

CurveSet parseObjCurves(std::string_view text, const std::string& path) {
    // Positive indices may refer to vertices defined later in the file, so
    // they are resolved once all vertices are known.
    struct PendingIndex {
        int64_t index;  // 1-based, absolute
        size_t line;
    };
    std::vector<Vec3> vertices;
    std::vector<std::vector<PendingIndex>> polylines;

    forEachLine(text, [&](size_t lineNo, std::string_view raw) {
        const auto fail = [&](const std::string& what) {
            throw InputError(path + ":" + std::to_string(lineNo) + ": " + what);
        };
        const std::string_view line = trim(raw.substr(0, raw.find('#')));
        const std::vector<std::string_view> tok = splitWhitespace(line);
        if (tok.empty()) return;
        if (tok[0] == "v") {
            // "v x y z", optionally followed by w or by r g b (vertex colours):
            // all must be numbers, only x y z are used.
            double xyz[3] = {0, 0, 0};
            bool ok = tok.size() >= 4;
            for (size_t k = 1; ok && k < tok.size(); ++k) {
                double value;
                ok = parseNumber(tok[k], &value);
                if (ok && k <= 3) xyz[k - 1] = value;
            }
            if (!ok) fail("expected 'v x y z' with numbers, got '" + printable(line) + "'");
            for (int k = 0; k < 3; ++k)
                if (!std::isfinite(xyz[k]) || std::abs(xyz[k]) > kFloatMax)
                    fail("vertex coordinate '" + std::string(tok[static_cast<size_t>(k) + 1]) +
                         "' is not a finite number in float range");
            vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
        } else if (tok[0] == "l") {
            if (tok.size() < 3)
                fail("a line element needs at least 2 vertex indices, got '" + printable(line) +
                     "'");
            std::vector<PendingIndex>& indices = polylines.emplace_back();
            indices.reserve(tok.size() - 1);
            for (size_t k = 1; k < tok.size(); ++k) {
                // "l v/vt" is allowed; only the vertex index matters here.
                const std::string_view vertexToken = tok[k].substr(0, tok[k].find('/'));
                int64_t index = 0;
                if (!parseNumber(vertexToken, &index) || index == 0)
                    fail("invalid vertex index '" + printable(tok[k]) +
                         "' (expected a non-zero integer: 1-based, or negative relative)");
                if (index < 0) {
                    const auto defined = static_cast<int64_t>(vertices.size());
                    if (index < -defined)
                        fail("vertex index " + std::to_string(index) + " out of range: only " +
                             std::to_string(defined) + " vertices are defined before this line");
                    index += defined + 1;
                }
                indices.push_back({index, lineNo});
            }
        }
        // Everything else (vn, vt, f, o, g, s, usemtl, mtllib, ...) is not a curve.
    });

    if (polylines.empty()) throw InputError(path + ": no curves (no 'l' elements)");
    CurveSet set;
    set.curves.reserve(polylines.size());
    for (const std::vector<PendingIndex>& indices : polylines) {
        Curve& curve = set.curves.emplace_back();
        curve.points.reserve(indices.size());
        for (const PendingIndex& p : indices) {
            if (p.index > static_cast<int64_t>(vertices.size()))
                throw InputError(path + ":" + std::to_string(p.line) + ": vertex index " +
                                 std::to_string(p.index) + " out of range (the file has " +
                                 std::to_string(vertices.size()) + " vertices)");
            curve.points.push_back(vertices[static_cast<size_t>(p.index - 1)]);
        }
    }
    return set;
}

// ---------------------------------------------------------------------------
// Writers: what they write, the readers above read back.

namespace {

[[noreturn]] void cannotWrite(const std::string& path, const std::string& what) {
    throw InputError("cannot write '" + path + "': " + what);
}

// InputError "cannot write '<path>': ..." unless the readers accept `set`'s
// curves as such: at least one curve, each of at least 2 points.
void checkWritable(const CurveSet& set, const std::string& path) {
    const auto fail = [&](const std::string& what) { cannotWrite(path, what); };
    if (set.curves.empty()) fail("no curves (a curve file holds at least one)");
    for (size_t i = 0; i < set.curves.size(); ++i)
        if (set.curves[i].points.size() < 2)
            fail("curve " + std::to_string(i) + " has " +
                 std::to_string(set.curves[i].points.size()) +
                 (set.curves[i].points.size() == 1 ? " point" : " points") +
                 " (a curve needs at least 2)");
}

}  // namespace

std::string formatBcc(const CurveSet& set, std::string_view info, const std::string& path) {
    const auto fail = [&](const std::string& what) { cannotWrite(path, what); };
    checkWritable(set, path);
    const CurveBasis basis = set.curves.front().basis;
    for (size_t i = 0; i < set.curves.size(); ++i)
        if (set.curves[i].basis != basis)
            fail("curve " + std::to_string(i) + " and curve 0 have different bases (BCC " +
                 "has one curve type per file)");
    std::string out;
    out.reserve(kBccHeaderSize + 4 * set.curves.size() + kBccPointSize * set.pointCount());
    out += "BCC";
    out += static_cast<char>(0x44);
    out += basis == CurveBasis::CatmullRom ? "C0" : "PL";
    out += static_cast<char>(3);  // dimensions
    out += static_cast<char>(2);  // up dimension: z
    storeLittleEndian<uint64_t>(&out, set.curves.size());
    storeLittleEndian<uint64_t>(&out, set.pointCount());
    // Keep a terminating NUL: readers treat fileInfo as a C string.
    const size_t infoLength = std::min(info.size(), kBccInfoSize - 1);
    out.append(info.data(), infoLength);
    out.append(kBccInfoSize - infoLength, '\0');
    for (size_t i = 0; i < set.curves.size(); ++i) {
        const Curve& curve = set.curves[i];
        if (curve.points.size() > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
            fail("curve " + std::to_string(i) + " has more than 2^31-1 points");
        const auto n = static_cast<int32_t>(curve.points.size());
        storeLittleEndian<int32_t>(&out, curve.closed ? -n : n);
        for (size_t j = 0; j < curve.points.size(); ++j) {
            for (int k = 0; k < 3; ++k) {
                const auto f = static_cast<float>(curve.points[j][k]);
                if (!std::isfinite(f))
                    fail("curve " + std::to_string(i) + " point " + std::to_string(j) +
                         " has a coordinate that is not finite in float32");
                storeLittleEndian<float>(&out, f);
            }
        }
    }
    return out;
}

void writeBcc(const std::string& path, const CurveSet& set, std::string_view info) {
    writeFileAtomic(path, formatBcc(set, info, path));
}

namespace {

// `v` as %.9g, exact for float32 values; as %.17g where %.9g would round
// beyond the float range that the text reader allows (FLT_MAX itself prints
// as 3.40282347e+38, above FLT_MAX).
int formatCoordinate(char* buf, size_t size, double v) {
    const int n = std::snprintf(buf, size, "%.9g", v);
    if (std::abs(v) < 3.4e38 || std::abs(std::strtod(buf, nullptr)) <= kFloatMax) return n;
    return std::snprintf(buf, size, "%.17g", v);
}

}  // namespace

std::string formatCurveText(const CurveSet& set, const std::string& path) {
    const auto fail = [&](const std::string& what) { cannotWrite(path, what); };
    checkWritable(set, path);
    const bool withRadii = !set.curves.front().radii.empty();
    for (size_t i = 0; i < set.curves.size(); ++i) {
        const Curve& curve = set.curves[i];
        if (curve.radii.empty() == withRadii)
            fail("curve " + std::to_string(i) + (withRadii ? " has no radii" : " has radii") +
                 " but curve 0 " + (withRadii ? "has" : "has none") +
                 " (the text format gives every point of a file a radius, or none)");
        if (withRadii && curve.radii.size() != curve.points.size())
            fail("curve " + std::to_string(i) + " has " + std::to_string(curve.points.size()) +
                 " points but " + std::to_string(curve.radii.size()) + " radii");
        for (size_t j = 0; j < curve.points.size(); ++j) {
            for (int k = 0; k < 3; ++k)
                if (!(std::abs(curve.points[j][k]) <= kFloatMax))
                    fail("curve " + std::to_string(i) + " point " + std::to_string(j) +
                         " has a coordinate that is not finite in float range");
            if (withRadii) {
                const auto r = static_cast<float>(curve.radii[j]);
                if (!std::isfinite(r) || !(r > 0))
                    fail("curve " + std::to_string(i) + " point " + std::to_string(j) +
                         " has a radius that is not finite and > 0 in float32");
            }
        }
    }
    std::string out =
        "# weft curves: one 'x y z [radius]' point per line, a blank line between "
        "curves\n";
    char buf[128];
    for (size_t i = 0; i < set.curves.size(); ++i) {
        const Curve& curve = set.curves[i];
        if (i > 0) out += '\n';
        if (curve.closed) out += "# closed\n";
        for (size_t j = 0; j < curve.points.size(); ++j) {
            for (int k = 0; k < 3; ++k) {
                if (k > 0) out += ' ';
                out.append(buf, static_cast<size_t>(
                                    formatCoordinate(buf, sizeof buf, curve.points[j][k])));
            }
            if (withRadii) {
                const int n = std::snprintf(buf, sizeof buf, " %.9g", curve.radii[j]);
                out.append(buf, static_cast<size_t>(n));
            }
            out += '\n';
        }
    }
    return out;
}

void writeCurveText(const std::string& path, const CurveSet& set) {
    writeFileAtomic(path, formatCurveText(set, path));
}

}  // namespace weft
