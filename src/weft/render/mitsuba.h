// weft/render/mitsuba.h — Mitsuba 3 scene files in and out (issue 46, docs/mitsuba.md).
//
// importMitsubaScene reads the subset of Mitsuba 3's XML that yarn scenes use
// (a perspective sensor with an hdrfilm and a sampler, the path integrator,
// constant and envmap emitters, spheres with an area emitter, linearcurve and
// bsplinecurve shapes, obj meshes, bsdfs by id or nested; `<default>` and
// `$name` substitution) into a weft scene folder. Each curve shape's bsdf
// becomes a weft yarn model through a mapping file (bsdf id -> the keys of a
// yarn entry: model, plies, ply_twist, colour, ...) or one model for all.
// Anything outside the subset is an InputError naming the file, the line and
// the element's path (`scene.xml:12: scene/shape[2]/bsdf: ...`): nothing is
// skipped silently; what is read approximately (a Gaussian pixel filter as
// weft's box) is listed in `notes`.
//
// exportMitsubaScene writes a weft scene as that subset: scene.xml, the yarn
// curves as linearcurve files (or, with fibers, the explicit fibers of fiber
// mode), the meshes, environment images, and weft-models.json mapping each
// yarn's stand-in bsdf back to its weft model, so that import(export(s))
// draws what s draws, and import -> export -> import is the identity.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "weft/render/scene_file.h"

namespace weft::render {

struct MitsubaImportOptions {
    std::string model;    // --model: the weft model of every curve shape without a mapping
    std::string mapping;  // --models MAP.json: bsdf id -> yarn keys; "" : weft-models.json
                          // beside the XML when there is one
    std::vector<std::pair<std::string, std::string>> defines;  // -D NAME=VALUE, over <default>
};

struct MitsubaImport {
    nlohmann::json scene;  // scene.json, its files relative to the output folder
    std::vector<std::pair<std::string, std::string>> files;  // (relative name, bytes)
    std::vector<std::string> notes;                          // what was read approximately
};

MitsubaImport importMitsubaScene(const std::string& xmlPath, const MitsubaImportOptions& options);
// The same on XML text (`xmlPath` names it in messages; the files it names
// resolve against `baseDir`): the fuzz harness's entry.
MitsubaImport importMitsubaText(std::string text, const std::string& xmlPath,
                                const std::string& baseDir, const MitsubaImportOptions& options);

struct MitsubaExport {
    std::vector<std::pair<std::string, std::string>> files;  // scene.xml first; (name, bytes)
    std::vector<std::string> notes;
};

// fibers: the yarns as the fibers fiber mode draws (each a linearcurve), not
// their centre lines.
MitsubaExport exportMitsubaScene(const SceneDesc& scene, bool fibers);

// Writes files into `dir` as one folder (core/file.h TempDirCommit). An
// existing `dir` is replaced only when it holds nothing but what an import
// or export writes (scene.json, scene.xml, weft-models.json, curves/,
// fibers/, meshes/, models/, textures/); otherwise InputError.
void writeSceneFolder(const std::vector<std::pair<std::string, std::string>>& files,
                      const std::string& dir);

}  // namespace weft::render
