#include "weft/core/text_parse.h"
#include "weft/core/curve_io.h"

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>

#include "weft/core/error.h"
#include "weft/core/file.h"

namespace weft {

static_assert(std::endian::native == std::endian::little,
              "the BCC reader and writer assume a little-endian host");

namespace {

constexpr size_t kBccHeaderSize = 64;
constexpr size_t kBccInfoSize = 40;

template <typename T>
T loadLE(const char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

template <typename T>
void storeLE(std::string* out, T v) {
    char buf[sizeof v];
    std::memcpy(buf, &v, sizeof v);
    out->append(buf, sizeof v);
}


}  // namespace

size_t CurveSet::pointCount() const {
    size_t n = 0;
    for (const auto& c : curves) n += c.size();
    return n;
}

// ---------------------------------------------------------------------------
// BCC

CurveSet readBcc(const std::string& path) {
    const std::string bytes = readFile(path);
    const auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
    if (bytes.size() < kBccHeaderSize)
        fail("truncated: a BCC header is 64 bytes but the file has " +
             std::to_string(bytes.size()));
    const char* h = bytes.data();
    if (std::string_view(h, 3) != "BCC")
        fail("not a BCC file (signature '" + printable(std::string_view(h, 3)) +
             "', expected 'BCC')");
    const auto byteCount = static_cast<unsigned char>(h[3]);
    if (byteCount != 0x44) {
        char buf[8];
        std::snprintf(buf, sizeof buf, "0x%02x", byteCount);
        fail(std::string("unsupported BCC byte count ") + buf +
             " (only 0x44, 4-byte integers and floats, is supported)");
    }
    CurveSet set;
    const std::string_view type(h + 4, 2);
    if (type == "PL") {
        set.basis = CurveSet::Basis::Polyline;
    } else if (type == "C0") {
        set.basis = CurveSet::Basis::CatmullRom;
    } else {
        fail("unsupported BCC curve type '" + printable(type) +
             "' (supported: 'PL' polyline, 'C0' uniform Catmull-Rom)");
    }
    const int dims = static_cast<unsigned char>(h[6]);
    if (dims != 3)
        fail("unsupported BCC dimension count " + std::to_string(dims) + " (only 3 is supported)");
    const auto curveCount = loadLE<uint64_t>(h + 8);
    const auto totalPoints = loadLE<uint64_t>(h + 16);

    // Each curve needs at least its 4-byte count: bound curveCount by the file
    // size before reserving anything.
    const size_t bodySize = bytes.size() - kBccHeaderSize;
    if (curveCount > bodySize / 4)
        fail("truncated: the header declares " + std::to_string(curveCount) +
             " curves but the file has room for at most " + std::to_string(bodySize / 4));
    set.curves.resize(curveCount);
    set.radii.resize(curveCount);
    set.closed.resize(curveCount);

    size_t offset = kBccHeaderSize;
    uint64_t pointsRead = 0;
    for (size_t i = 0; i < curveCount; ++i) {
        if (bytes.size() - offset < 4)
            fail("truncated: the file ends before the point count of curve " + std::to_string(i) +
                 " of " + std::to_string(curveCount));
        const auto signedCount = loadLE<int32_t>(h + offset);
        offset += 4;
        if (signedCount == 0 || signedCount == std::numeric_limits<int32_t>::min())
            fail("curve " + std::to_string(i) + " has an invalid point count " +
                 std::to_string(signedCount));
        const size_t count =
            static_cast<size_t>(signedCount < 0 ? -int64_t(signedCount) : int64_t(signedCount));
        const size_t available = (bytes.size() - offset) / 12;
        if (count > available)
            fail("truncated: curve " + std::to_string(i) + " declares " + std::to_string(count) +
                 " points but the file ends after " + std::to_string(available));
        std::vector<Vec3>& pts = set.curves[i];
        pts.resize(count);
        for (size_t j = 0; j < count; ++j, offset += 12) {
            const float x = loadLE<float>(h + offset), y = loadLE<float>(h + offset + 4),
                        z = loadLE<float>(h + offset + 8);
            if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
                fail("curve " + std::to_string(i) + " point " + std::to_string(j) +
                     " has a non-finite coordinate");
            pts[j] = Vec3(x, y, z);
        }
        set.closed[i] = signedCount < 0;
        pointsRead += count;
    }
    if (offset != bytes.size())
        fail(std::to_string(bytes.size() - offset) + " unexpected bytes after the " +
             std::to_string(curveCount) + " curves the header declares");
    if (pointsRead != totalPoints)
        fail("the header declares " + std::to_string(totalPoints) +
             " control points but the curves hold " + std::to_string(pointsRead));
    return set;
}

void writeBcc(const std::string& path, const CurveSet& set, std::string_view info) {
    const auto fail = [&](const std::string& what) {
        throw InputError("cannot write '" + path + "': " + what);
    };
    std::string out;
    out.reserve(kBccHeaderSize + 4 * set.curves.size() + 12 * set.pointCount());
    out += "BCC";
    out += static_cast<char>(0x44);
    out += set.basis == CurveSet::Basis::CatmullRom ? "C0" : "PL";
    out += static_cast<char>(3);  // dimensions
    out += static_cast<char>(2);  // up dimension: z
    storeLE<uint64_t>(&out, set.curves.size());
    storeLE<uint64_t>(&out, set.pointCount());
    // Keep a terminating NUL: readers treat fileInfo as a C string.
    const size_t infoLen = std::min(info.size(), kBccInfoSize - 1);
    out.append(info.data(), infoLen);
    out.append(kBccInfoSize - infoLen, '\0');

    for (size_t i = 0; i < set.curves.size(); ++i) {
        const std::vector<Vec3>& pts = set.curves[i];
        if (pts.empty()) fail("curve " + std::to_string(i) + " has no points");
        if (pts.size() > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
            fail("curve " + std::to_string(i) + " has more than 2^31-1 points");
        const auto n = static_cast<int32_t>(pts.size());
        storeLE<int32_t>(&out, set.isClosed(i) ? -n : n);
        for (size_t j = 0; j < pts.size(); ++j) {
            for (int k = 0; k < 3; ++k) {
                const auto f = static_cast<float>(pts[j][k]);
                if (!std::isfinite(f))
                    fail("curve " + std::to_string(i) + " point " + std::to_string(j) +
                         " has a coordinate that is not finite in float32");
                storeLE<float>(&out, f);
            }
        }
    }
    writeFileAtomic(path, out);
}

// ---------------------------------------------------------------------------
// Text polylines

CurveSet parseCurveText(std::string_view text, const std::string& path) {
    CurveSet set;
    bool inCurve = false, pendingClosed = false;
    size_t curveStartLine = 0;
    forEachLine(text, [&](size_t lineNo, std::string_view raw) {
        const auto fail = [&](const std::string& what) {
            throw InputError(path + ":" + std::to_string(lineNo) + ": " + what);
        };
        const std::string_view line = trim(raw);
        if (line.empty()) {
            inCurve = false;
            return;
        }
        if (line[0] == '#') {
            if (!inCurve && trim(line.substr(1)) == "closed") pendingClosed = true;
            return;
        }
        const std::vector<std::string_view> tok = splitWhitespace(line);
        double v[4];
        bool ok = tok.size() == 3 || tok.size() == 4;
        for (size_t k = 0; ok && k < tok.size(); ++k) ok = parseNumber(tok[k], &v[k]);
        if (!ok) fail("expected 3 or 4 numbers (x y z [radius]), got '" + printable(line) + "'");
        for (size_t k = 0; k < tok.size(); ++k)
            if (!std::isfinite(v[k]))
                fail("non-finite number '" + std::string(tok[k]) + "' in '" + printable(line) +
                     "'");
        const bool hasRadius = tok.size() == 4;
        if (hasRadius && v[3] < 0)
            fail("negative radius " + std::string(tok[3]) + " (radii must be >= 0)");
        if (!inCurve) {
            set.curves.emplace_back();
            set.radii.emplace_back();
            set.closed.push_back(pendingClosed);
            pendingClosed = false;
            inCurve = true;
            curveStartLine = lineNo;
        } else if (hasRadius != !set.radii.back().empty()) {
            fail(std::string(hasRadius ? "point has a radius but the earlier points"
                                       : "point has no radius but the earlier points") +
                 " of this curve (from line " + std::to_string(curveStartLine) + ") " +
                 (hasRadius ? "have none" : "have one") +
                 "; give every point of a curve a radius, or none");
        }
        set.curves.back().emplace_back(v[0], v[1], v[2]);
        if (hasRadius) set.radii.back().push_back(v[3]);
    });
    return set;
}

CurveSet readCurveText(const std::string& path) { return parseCurveText(readFile(path), path); }

std::string formatCurveText(const CurveSet& set) {
    std::string out =
        "# weft curves: one 'x y z [radius]' point per line, a blank line between "
        "curves\n";
    char buf[128];
    bool first = true;
    for (size_t i = 0; i < set.curves.size(); ++i) {
        const std::vector<Vec3>& pts = set.curves[i];
        if (pts.empty()) continue;
        if (!first) out += '\n';
        first = false;
        if (set.isClosed(i)) out += "# closed\n";
        const bool withRadii = set.hasRadii(i);
        for (size_t j = 0; j < pts.size(); ++j) {
            int n = std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g", pts[j].x, pts[j].y, pts[j].z);
            out.append(buf, static_cast<size_t>(n));
            if (withRadii) {
                n = std::snprintf(buf, sizeof buf, " %.9g", set.radii[i][j]);
                out.append(buf, static_cast<size_t>(n));
            }
            out += '\n';
        }
    }
    return out;
}

void writeCurveText(const std::string& path, const CurveSet& set) {
    for (size_t i = 0; i < set.curves.size(); ++i)
        if (set.hasRadii(i) && set.radii[i].size() != set.curves[i].size())
            throw InputError("cannot write '" + path + "': curve " + std::to_string(i) + " has " +
                             std::to_string(set.curves[i].size()) + " points but " +
                             std::to_string(set.radii[i].size()) + " radii");
    writeFileAtomic(path, formatCurveText(set));
}

// ---------------------------------------------------------------------------
// OBJ

CurveSet readObjCurves(const std::string& path) {
    const std::string text = readFile(path);
    struct PendingIndex {
        long long index;  // 1-based absolute
        size_t line;
    };
    std::vector<Vec3> vertices;
    std::vector<std::vector<PendingIndex>> lines;
    std::string joined;  // a logical line assembled from '\'-continued lines
    size_t joinedStart = 0;

    const auto handle = [&](size_t lineNo, std::string_view line) {
        const auto fail = [&](const std::string& what) {
            throw InputError(path + ":" + std::to_string(lineNo) + ": " + what);
        };
        const size_t hash = line.find('#');
        if (hash != std::string_view::npos) line = line.substr(0, hash);
        const std::vector<std::string_view> tok = splitWhitespace(trim(line));
        if (tok.empty()) return;
        if (tok[0] == "v") {
            double v[3];
            bool ok = tok.size() >= 4;
            for (size_t k = 0; ok && k < 3; ++k) ok = parseNumber(tok[k + 1], &v[k]);
            if (!ok) fail("expected 'v x y z', got '" + printable(trim(line)) + "'");
            if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
                fail("non-finite vertex coordinate in '" + printable(trim(line)) + "'");
            vertices.emplace_back(v[0], v[1], v[2]);
        } else if (tok[0] == "l") {
            if (tok.size() < 3)
                fail("a line element needs at least 2 vertex indices, got '" +
                     printable(trim(line)) + "'");
            std::vector<PendingIndex>& idx = lines.emplace_back();
            for (size_t k = 1; k < tok.size(); ++k) {
                // "l v/vt" is allowed; only the vertex index matters here.
                const std::string_view vtok = tok[k].substr(0, tok[k].find('/'));
                long long i = 0;
                if (!parseNumber(vtok, &i) || i == 0)
                    fail("invalid vertex index '" + printable(tok[k]) +
                         "' (expected a non-zero integer, 1-based or negative relative)");
                if (i < 0) {
                    const long long abs = static_cast<long long>(vertices.size()) + 1 + i;
                    if (abs < 1)
                        fail("relative vertex index " + std::to_string(i) + " refers before the " +
                             "first vertex (" + std::to_string(vertices.size()) +
                             " vertices so far)");
                    i = abs;
                }
                idx.push_back({i, lineNo});
            }
        }
    };

    forEachLine(text, [&](size_t lineNo, std::string_view line) {
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (joined.empty()) joinedStart = lineNo;
        if (!line.empty() && line.back() == '\\') {
            joined.append(line.substr(0, line.size() - 1));
            joined += ' ';
            return;
        }
        if (joined.empty()) {
            handle(lineNo, line);
        } else {
            joined.append(line);
            handle(joinedStart, joined);
            joined.clear();
        }
    });
    if (!joined.empty()) handle(joinedStart, joined);

    CurveSet set;
    set.curves.reserve(lines.size());
    for (const std::vector<PendingIndex>& idx : lines) {
        std::vector<Vec3>& pts = set.curves.emplace_back();
        pts.reserve(idx.size());
        for (const PendingIndex& p : idx) {
            if (p.index > static_cast<long long>(vertices.size()))
                throw InputError(path + ":" + std::to_string(p.line) + ": vertex index " +
                                 std::to_string(p.index) + " out of range (the file has " +
                                 std::to_string(vertices.size()) + " vertices)");
            pts.push_back(vertices[static_cast<size_t>(p.index - 1)]);
        }
    }
    set.radii.resize(set.curves.size());
    set.closed.resize(set.curves.size(), false);
    return set;
}

}  // namespace weft
