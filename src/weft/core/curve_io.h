// weft/core/curve_io.h — yarn and fiber centre-line files.
//
// Three formats, all read into a CurveSet:
//  - BCC, Cem Yuksel's binary curve collection (http://www.cemyuksel.com/
//    research/hairmodels/): a 64-byte header (sign "BCC", byteCount 0x44 =
//    4-byte ints and floats, curveType "PL" polyline or "C0" uniform
//    Catmull-Rom, dimensions 3, upDimension, uint64 curveCount, uint64
//    totalControlPointCount, char fileInfo[40]), then per curve an int32 point
//    count (negative: closed curve) and that many float32 xyz triples.
//  - Text: one "x y z [radius]" point per line, blank lines between curves,
//    '#' comment lines. A "# closed" comment line directly before a curve's
//    first point marks it closed (written by formatCurveText).
//  - Wavefront OBJ: "v x y z" vertices and "l i j k ..." polylines (1-based,
//    negative = relative to the last vertex); other elements are ignored.
// Every problem in a file is an InputError naming the file (and line, for the
// text formats).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "weft/core/vec.h"

namespace weft {

struct CurveSet {
    // How control points are joined: straight segments, or a uniform
    // Catmull-Rom spline through them (BCC "C0"). Readers never convert.
    enum class Basis { Polyline, CatmullRom };

    std::vector<std::vector<Vec3>> curves;
    // Parallel to curves: per-point radii of curve i, or empty if it has none.
    // May be empty altogether when no curve has radii.
    std::vector<std::vector<double>> radii;
    // Parallel to curves: whether the last point joins the first. May be empty
    // (all open).
    std::vector<bool> closed;
    Basis basis = Basis::Polyline;

    size_t pointCount() const;
    bool isClosed(size_t i) const { return i < closed.size() && closed[i]; }
    bool hasRadii(size_t i) const { return i < radii.size() && !radii[i].empty(); }
};

// Reads a BCC file of type "PL" or "C0" (sets basis; no conversion). Curve
// numbers in messages count from 0.
CurveSet readBcc(const std::string& path);
// Writes a BCC file atomically: type "PL" (or "C0" if set.basis is
// CatmullRom), closed curves as negative counts, `info` (at most 39 bytes
// kept) in fileInfo. BCC has no radii: they are not written. InputError if a
// coordinate is not finite in float32 or a curve is empty or too long.
void writeBcc(const std::string& path, const CurveSet& set, std::string_view info);

// Reads the text polyline format (see above). Errors name file:line.
CurveSet readCurveText(const std::string& path);
// Same, on text already in memory; `pathForErrors` names it in messages.
CurveSet parseCurveText(std::string_view text, const std::string& pathForErrors);
// The text format of `set`, with %.9g numbers (exact for float32 data).
std::string formatCurveText(const CurveSet& set);
void writeCurveText(const std::string& path, const CurveSet& set);

// Reads the polylines ("l" elements) of an OBJ file. Errors name file:line.
CurveSet readObjCurves(const std::string& path);

}  // namespace weft
