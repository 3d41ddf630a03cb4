// weft/render/curves.h — yarn curve files as the renderer reads them (issue 7).
//
// readCurves loads a .bcc, .txt or .obj file (docs/design.md section 8) into a
// CurveSet: per curve its control points, optional per-point radii, whether
// it is closed and how its control points are joined (CurveBasis). Nothing is
// resampled or converted: a Catmull-Rom curve comes back as its control
// points. The formats, their fields and every check are described in
// docs/curves.md.
//
// The readers are strict: a file is either read completely or rejected with an
// InputError that names the file and where it went wrong (BCC: byte offset and
// curve index; text and OBJ: file:line). They never allocate from a count
// read from the file before checking it against the bytes that remain, so a
// corrupt or hostile file cannot make them allocate more than a small multiple
// of its own size.
//
// core/curve_io.h holds the older, more lenient readers that `weft ply` and
// `weft gather` use (and whose text output, "# closed" marker included, these
// readers accept); these types live in weft::render so the two CurveSets do
// not collide.
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "weft/core/rgb.h"
#include "weft/core/vec.h"

namespace weft::render {

// How a curve's control points are joined: straight segments (BCC "PL", text,
// OBJ) or a uniform Catmull-Rom spline through them (BCC "C0").
enum class CurveBasis { Polyline, CatmullRom };

struct Curve {
    std::vector<Vec3> points;  // control points, at least 2
    std::vector<float> radii;  // one per point, or empty when the file has none
    bool closed = false;       // the last point joins the first
    CurveBasis basis = CurveBasis::Polyline;
    // The fiber colour C_TT at each point (a scene's "vertex_colours" file,
    // readVertexColours), or empty: the yarn entry's colour.
    std::vector<Rgb> colours;
};

struct CurveSet {
    std::vector<Curve> curves;

    size_t pointCount() const;
};

// Axis-aligned box; empty (lo > hi) until a point is added.
struct Bounds3 {
    Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            std::numeric_limits<double>::infinity()};
    Vec3 hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
            -std::numeric_limits<double>::infinity()};

    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    void extend(const Vec3& p);
};

// Reads `path` by its extension (.bcc, .txt, .obj, case-insensitive); any other
// extension is an InputError naming the file and the allowed ones.
CurveSet readCurves(const std::string& path);

// The three readers on bytes already in memory; `pathForErrors` names them in
// messages. readCurves is readFile + one of these.
CurveSet parseBccCurves(std::string_view bytes, const std::string& pathForErrors);
CurveSet parseTextCurves(std::string_view text, const std::string& pathForErrors);
CurveSet parseObjCurves(std::string_view text, const std::string& pathForErrors);

// Reads a vertex colour file (docs/scene-format.md, "vertex_colours") into
// the colours of `set`'s curves: text, one "r g b" line per control point,
// each value in [0, 1], the curves in the order of the curve file and
// separated by blank lines; '#' starts a comment. InputError naming
// path:line for a malformed line or a value out of range, and the curve
// when the colour file's curves or their points do not match the set's.
void readVertexColours(const std::string& path, CurveSet* set);
void parseVertexColours(std::string_view text, const std::string& pathForErrors, CurveSet* set);

// Spans between consecutive control points: n - 1 for an open curve of n
// points, n for a closed one, whatever the basis (an interpolating Catmull-Rom
// curve has one span per pair of neighbouring control points as well).
size_t segmentCount(const Curve& curve);
size_t segmentCount(const CurveSet& set);

// Box around all control points (for Catmull-Rom curves the spline may bulge
// slightly beyond it). Radii are not included.
Bounds3 bounds(const CurveSet& set);

}  // namespace weft::render
