// weft/core/curves.h — yarn and fiber curve files: the one reader and writer.
//
// readCurves loads a .bcc, .txt or .obj file (docs/design.md section 8,
// docs/curves.md) into a CurveSet: per curve its control points, optional
// per-point radii, whether it is closed and how its control points are joined
// (CurveBasis). Nothing is resampled or converted: a Catmull-Rom curve comes
// back as its control points. `weft render`, `weft curves info`, the scene
// generator and the tests all read through it; `weft ply`, `weft gather`
// (ply.txt) and `weft scene` write through writeBcc and writeCurveText.
//
// The readers are strict: a file is either read completely or rejected with an
// InputError that names the file and where it went wrong (BCC: byte offset and
// curve index; text and OBJ: file:line). They never allocate from a count
// read from the file before checking it against the bytes that remain, so a
// corrupt or hostile file cannot make them allocate more than a small multiple
// of its own size. Radii are kept at float32 precision, as the renderer draws
// them. The writers refuse what the readers would refuse, so that whatever
// they write reads back.
//
// The fiber colours of a curve (Curve::colours) come from a scene's vertex
// colour file, which the renderer reads (render/curves.h).
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "weft/core/rgb.h"
#include "weft/core/vec.h"

namespace weft {

// How a curve's control points are joined: straight segments (BCC "PL", text,
// OBJ) or a uniform Catmull-Rom spline through them (BCC "C0").
enum class CurveBasis { Polyline, CatmullRom };

struct Curve {
    std::vector<Vec3> points;   // control points, at least 2
    std::vector<double> radii;  // one per point, or empty when the file has none
    bool closed = false;        // the last point joins the first
    CurveBasis basis = CurveBasis::Polyline;
    // The fiber colour C_TT at each point (a scene's "vertex_colours" file,
    // render::readVertexColours), or empty: the yarn entry's colour.
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

// A BCC file of `set`: type "PL", or "C0" when its curves are Catmull-Rom
// (BCC has one type per file: curves of both bases are an InputError), closed
// curves as negative counts, up dimension 2 (z), `info` (at most 39 bytes
// kept) in fileInfo. BCC has no radii and no colours: they are not written.
// InputError naming `pathForErrors` for a set with no curves, a curve of
// fewer than 2 points or of more than 2^31 - 1, or a coordinate that is not
// finite in float32. writeBcc writes it atomically.
std::string formatBcc(const CurveSet& set, std::string_view info, const std::string& pathForErrors);
void writeBcc(const std::string& path, const CurveSet& set, std::string_view info);

// The text format of `set`: a header comment, "# closed" before each closed
// curve, one "x y z [radius]" line per point with %.9g numbers (exact for
// float32 data), a blank line between curves. The text format has no basis:
// a Catmull-Rom curve reads back as a polyline through its control points.
// Colours are not written. InputError naming `pathForErrors` unless the
// readers would read it back: at least one curve, each of at least 2 points,
// coordinates finite in float range, radii on every curve or on none, one per
// point, each finite and > 0 in float32. writeCurveText writes it atomically.
std::string formatCurveText(const CurveSet& set, const std::string& pathForErrors);
void writeCurveText(const std::string& path, const CurveSet& set);

// Spans between consecutive control points: n - 1 for an open curve of n
// points, n for a closed one, whatever the basis (an interpolating Catmull-Rom
// curve has one span per pair of neighbouring control points as well).
size_t segmentCount(const Curve& curve);
size_t segmentCount(const CurveSet& set);

// The control points as rows (curve index, x, y, z), in file order: the
// (n, 4) array of `weft curves points` and Python's curves_points.
std::vector<double> pointRows(const CurveSet& set);

// Box around all control points (for Catmull-Rom curves the spline may bulge
// slightly beyond it). Radii are not included.
Bounds3 bounds(const CurveSet& set);

}  // namespace weft
