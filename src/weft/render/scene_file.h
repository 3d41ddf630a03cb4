// weft/render/scene_file.h — the scene file of `weft render` (issue 7, docs/design.md 8).
//
// A JSON object (every key documented in docs/scene-format.md):
//   {
//     "camera": {"from": [x,y,z], "to": [x,y,z], "up": [0,1,0], "fov_deg": 30},
//     "film":   {"width": 512, "height": 512},
//     "render": {"spp": 64, "max_depth": 1000, "seed": 0, "sampler": "independent"},
//     "light_sampler": "uniform",   // or "power", or {"weights": [one per light]}
//     "lights": [ {"type": "sky", "scale": 1},
//                 {"type": "envmap", "file": "sky.exr", "scale": 1.0, "rotate_deg": 0},
//                 {"type": "sphere", "center": [x,y,z], "radius": r, "radiance": [r,g,b]},
//                 {"type": "constant", "radiance": [r,g,b]} ],
//     "yarns":  [ {"curves": "knit.bcc", "scale": 1.0, "radius": 0.02, "plies": 3,
//                  "ply_twist": 0.3, "model": "fleece.json", "mode": "neural"} ],
//     "objects": [ {"type": "rectangle", ...}, {"type": "mesh", "file": "arm.obj", ...} ]
//   }
// Lights are read by their registered type (light.h), yarn modes by name
// (yarn_mode.h). Parsing validates everything once: a missing required key,
// an unknown key, a key repeated in one object, a wrong type, a value out of range or a NaN
// is an InputError that names the scene file and the JSON path of the key
// (e.g. `scene.json: yarns[1].plies = 0 is out of range: allowed [1, 16]`).
// Relative file paths ("curves", "model", "file") are resolved against the
// folder of the scene file and stored absolute-or-as-joined; files are not
// opened here (their extensions are checked).
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "weft/core/family_box.h"
#include "weft/core/file.h"
#include "weft/core/rgb.h"
#include "weft/core/sample_stream.h"
#include "weft/core/vec.h"
#include "weft/render/light.h"
#include "weft/render/light_sampler.h"
#include "weft/render/scene_limits.h"
#include "weft/render/scene_objects.h"

namespace weft::render {

struct CameraDesc {
    Vec3 from, to;       // required; from != to
    Vec3 up{0, 1, 0};    // not parallel to to - from
    double fovDeg = 30;  // full field of view of the shorter image side, in (0, 180)
};

struct FilmDesc {
    int width = 512, height = 512;  // each in [1, 16384]
};

struct RenderDesc {
    int spp = 64;                                    // [1, 1 << 20]
    int maxDepth = 1000;                             // scattering events per path, [1, 10000]
    uint64_t seed = 0;                               // any non-negative integer
    SamplerKind sampler = SamplerKind::Independent;  // "independent" or "sobol"
    // The fibers' arrangement in fiber mode (scene.h fiberSeed): 0 is the
    // default one; any other integer an independent one of the same ply.
    uint64_t fiberSeed = 0;
};

struct YarnDesc {
    std::string curves;            // resolved path of a .bcc, .txt or .obj file (required)
    double scale = 1;              // multiplies positions; finite, > 0
    std::optional<double> radius;  // yarn radius in scene units (not multiplied by scale);
                                   // finite, > 0; absent: the file's per-point radii times
                                   // scale (an InputError at load if the file has none)
    int plies = 1;                 // [1, 16]
    double plyTwist = 0;           // finite, |ply_twist| <= 100; sign: + right-handed
    std::string model;             // resolved path of a MODEL.json from `weft fit` (required)
    // A family model's yarn (docs/family.md): required with a family model
    // (weft fit family), checked against its box; refused with any other.
    std::optional<YarnPoint> yarn;
    // The fiber colour C_TT of this yarn, each channel in [0, 1]; absent: the
    // model's. Fiber and dual mode use it with any model; neural mode needs a
    // colour-conditioned model (docs/colour.md).
    std::optional<Rgb> colour;
    // The colour the yarn should look (docs/colour.md, "Colour by
    // appearance"): sRGB-encoded, each channel in [0, 1] ("#rrggbb" in the
    // file is read as its bytes / 255). The scene finds the C_TT that gives it
    // from a colour model's appearance table, for every mode. Excludes
    // "colour" and "vertex_colours".
    std::optional<Rgb> appearance;
    // Resolved path of a vertex colour file (curves.h readVertexColours): a
    // C_TT per control point, interpolated along the curve (dyed and
    // space-dyed yarns); "" when absent. Excludes "colour".
    std::string vertexColours;
    // How the yarn is drawn and shaded: a registered drawing mode
    // (yarn_mode.h: "neural", "fiber", "dual"); "" when absent, which renders
    // neural. `weft render --mode` overrides every yarn's.
    std::string mode;
};

// An animation (issue 43, docs/render.md "Animation"): file names with a
// frame pattern ("knit.%04d.bcc": one %d or %0Nd, N in [1, 9]) read the
// file of each frame; frames first..last are rendered by
// `weft render --frames` (which may override them); turntableDeg turns the
// camera about the vertical (+y) through camera.to by that many degrees over
// the frames (frame f at turntableDeg (f - first) / (last - first + 1)).
struct AnimationDesc {
    int first = 0, last = -1;  // last < first: no range given
    double turntableDeg = 0;   // finite, |.| <= 3600
    bool hasRange() const { return last >= first; }
};

struct SceneDesc {
    std::string path;     // the scene file (for messages); "" when parsed from memory
    std::string baseDir;  // folder relative paths were resolved against
    CameraDesc camera;
    FilmDesc film;
    RenderDesc render;
    std::vector<std::shared_ptr<const LightDesc>> lights;  // empty: the procedural sky
    LightSamplerDesc lightSampler;  // "light_sampler": which light NEE samples (light_sampler.h)
    std::vector<YarnDesc> yarns;    // may be empty (an environment-only scene)
    std::vector<ObjectDesc> objects;  // floors, backdrops, meshes (scene_objects.h)
    AnimationDesc animation;          // "animation": {"frames": [first, last], "turntable_deg"}
};

// Largest frame number (and span) an animation takes.
inline constexpr int kMaxFrame = 9999999;
// Whether a file name holds a frame pattern (%d or %0Nd), and the name for
// frame f; InputError naming `what` for a malformed or repeated pattern.
bool hasFramePattern(const std::string& name);
std::string frameFileName(const std::string& pattern, int frame, const std::string& what);
// Whether any file of the scene (curves, vertex colours, meshes) is a frame pattern.
bool isAnimated(const SceneDesc& scene);
// The scene of frame `frame` of `first..last` (the range the render uses):
// every pattern filled in, the camera turned by the turntable.
SceneDesc sceneAtFrame(const SceneDesc& scene, int frame, int first, int last);

// Parses and validates a scene; `pathForErrors` names it in messages ("scene"
// when empty) and relative paths resolve against `baseDir`.
SceneDesc parseScene(const nlohmann::json& json, const std::string& pathForErrors,
                     const std::string& baseDir);
// The same on JSON text (a syntax error names the line and column; nesting
// deeper than 64 arrays and objects is rejected before parsing).
SceneDesc parseSceneText(std::string_view text, const std::string& pathForErrors,
                         const std::string& baseDir);
// Reads the file and parses it; relative paths resolve against its folder,
// made absolute (so the resolved paths do not depend on the working directory).
SceneDesc loadScene(const std::string& path);

// The scene as JSON with every key written (defaults included) and paths as
// stored; parseScene(toJson(s), ...) gives back s (a round-trip test).
nlohmann::json toJson(const SceneDesc& scene);

// Every file a render of the scene reads: the scene file itself
// (`scenePath`, when not empty), each yarn's curves and model, each envmap, each mesh,
// named by their JSON paths (for core/file.h's checkOutputsSpareInputs).
std::vector<CommandPath> sceneInputs(const SceneDesc& scene, const std::string& scenePath);

// 16 hex digits identifying what a render of the scene depends on: the
// canonical JSON of the scene (toJson, with paths replaced by the files'
// contents hashed) and the bytes of every referenced file. InputError naming
// a referenced file that cannot be read.
std::string sceneHash(const SceneDesc& scene);

}  // namespace weft::render
