// A scene's vertex colour files (render/curves.h).
#include "weft/render/curves.h"

#include <string>
#include <utility>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_message.h"
#include "weft/core/npy.h"
#include "weft/core/text_parse.h"

namespace weft::render {

void readVertexColours(const std::string& path, CurveSet* set) {
    const std::string ext = lowercaseExtension(path);
    if (ext == ".npy") {
        const NpyMatrix m = readNpyMatrix(path, 3, "vertex colours (one r, g, b row per point)");
        if (m.rows != set->pointCount())
            throw InputError(path + ": " + std::to_string(m.rows) + " colour rows but " +
                             std::to_string(set->pointCount()) +
                             " points in the curve file (one row per point, in the order "
                             "`weft curves points` writes)");
        size_t row = 0;
        for (Curve& curve : set->curves) {
            curve.colours.clear();
            for (size_t i = 0; i < curve.points.size(); ++i, ++row) {
                for (size_t k = 0; k < 3; ++k)
                    if (!(m(row, k) >= 0 && m(row, k) <= 1))
                        throw InputError(path + ": row " + std::to_string(row) + ", column " +
                                         std::to_string(k) + ": colour value " +
                                         formatNumber(m(row, k)) +
                                         " is out of range: allowed [0, 1]");
                curve.colours.emplace_back(m(row, 0), m(row, 1), m(row, 2));
            }
        }
        return;
    }
    if (ext != ".txt")
        throw InputError(path + ": unsupported vertex colour file extension '" +
                         (ext.empty() ? std::string("(none)") : ext) + "' (allowed: .txt, .npy)");
    parseVertexColours(readFile(path), path, set);
}

void parseVertexColours(std::string_view text, const std::string& path, CurveSet* set) {
    std::vector<std::vector<Rgb>> colours;
    std::vector<size_t> firstLine;  // of each colour curve, for messages
    bool inCurve = false;
    forEachLine(text, [&](size_t lineNo, std::string_view raw) {
        const auto fail = [&](const std::string& what) {
            throw InputError(path + ":" + std::to_string(lineNo) + ": " + what);
        };
        const std::string_view line = trim(raw.substr(0, raw.find('#')));
        if (line.empty()) {
            // A blank line ends a curve; a comment line does not.
            if (trim(raw).empty()) inCurve = false;
            return;
        }
        const std::vector<std::string_view> tok = splitWhitespace(line);
        double v[3];
        bool ok = tok.size() == 3;
        for (size_t k = 0; ok && k < 3; ++k) ok = parseNumber(tok[k], &v[k]);
        if (!ok) fail("expected a colour 'r g b' (3 numbers), got '" + printable(line) + "'");
        for (size_t k = 0; k < 3; ++k)
            if (!(v[k] >= 0 && v[k] <= 1))
                fail("colour value '" + std::string(tok[k]) + "' is out of range: allowed [0, 1]");
        if (!inCurve) {
            if (colours.size() == set->curves.size())
                fail("a colour for curve " + std::to_string(colours.size()) +
                     ", but the curve file has " + std::to_string(set->curves.size()) + " curves");
            colours.emplace_back();
            firstLine.push_back(lineNo);
            inCurve = true;
        }
        if (colours.back().size() == set->curves[colours.size() - 1].points.size())
            fail("more colours than the " +
                 std::to_string(set->curves[colours.size() - 1].points.size()) +
                 " points of curve " + std::to_string(colours.size() - 1) +
                 " (curves are separated by blank lines)");
        colours.back().emplace_back(v[0], v[1], v[2]);
    });
    for (size_t c = 0; c < set->curves.size(); ++c) {
        const size_t points = set->curves[c].points.size();
        const size_t given = c < colours.size() ? colours[c].size() : 0;
        if (given != points)
            throw InputError(path + (c < colours.size() ? ":" + std::to_string(firstLine[c]) : "") +
                             ": curve " + std::to_string(c) + " has " + std::to_string(given) +
                             " colours but " + std::to_string(points) +
                             " points in the curve file (one 'r g b' line per point)");
    }
    for (size_t c = 0; c < set->curves.size(); ++c) set->curves[c].colours = std::move(colours[c]);
}

}  // namespace weft::render
