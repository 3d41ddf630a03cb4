// weft/render/curves.h — what the renderer adds to the curve files of
// core/curves.h: a scene's vertex colour files.
//
// The curve files themselves (readCurves, CurveSet, the writers) live in
// core/curves.h, which every stage reads them through; this header includes it.
// A vertex colour file is part of the scene format (docs/scene-format.md,
// "vertex_colours"): only a scene gives one, and only the renderer reads it.
#pragma once

#include <string>
#include <string_view>

#include "weft/core/curves.h"

namespace weft::render {

// Reads a vertex colour file (docs/scene-format.md, "vertex_colours") into
// the colours of `set`'s curves: text, one "r g b" line per control point,
// each value in [0, 1], the curves in the order of the curve file and
// separated by blank lines; '#' starts a comment. InputError naming
// path:line for a malformed line or a value out of range, and the curve
// when the colour file's curves or their points do not match the set's. Or
// .npy: an (n, 3) float32 or float64 array, one row per control point in the
// curve file's order (`weft curves points`), n the set's point count.
void readVertexColours(const std::string& path, CurveSet* set);
void parseVertexColours(std::string_view text, const std::string& pathForErrors, CurveSet* set);

}  // namespace weft::render
