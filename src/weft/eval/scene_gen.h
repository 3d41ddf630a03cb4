// weft/eval/scene_gen.h — generated evaluation scenes for `weft render` (issue 8, docs/design.md
// 8-9).
//
// Three scenes, each one yarn set (one curve file, one fitted model) lit as in
// the paper's figures: the procedural sky (or an environment map) plus two
// sphere lights, a warm key light top-right and a cool fill light bottom-left
// of the view. Every yarn end is kept out of view (the yarns run on past the
// film's edges, extendEndsOutOfView in scene_gen.cpp): a cut end is a sphere
// cap in neural mode and splayed, flat-cut fibers in fiber mode, a difference
// no yarn model is meant to capture.
//   closeup  one gently curved open yarn across the frame (paper Fig. 8),
//            framed on a length of 8 R (frameBox), running on beyond the film.
//   weave    a plain weave of N warp yarns along x and N weft yarns along y,
//            sinusoidal in depth z; spacing and crimp amplitude chosen so that
//            crossing yarns touch with 1% clearance and never intersect
//            (weaveGeometry; derivation in docs/scenes.md). The film is
//            covered by the cells of the N x N yarns (frameCover); more yarns
//            lie around them so that the cloth fills the frame.
//   knit     a stockinette patch of N courses of N loops each, from Crane's
//            parametric plain-knit curve (K. Crane, "A Simple Parametric Model
//            of Plain-Knit Yarns", 2023): gamma(t) = (t + a sin 2t, h cos t,
//            d cos 2t), courses offset by w along y, scaled to the yarn radius
//            (knitGeometry; docs/scenes.md). The film is covered by N courses
//            of N loops; more courses and loops lie around them.
// Colours (--colours, issue 21, docs/colour.md): one C_TT for every yarn, or
// two: a striped knit (courses alternate colour every --stripe courses) and a
// two-colour check weave (warp and weft both in blocks of --stripe yarns,
// the warp blocks starting with the first colour and the weft blocks with
// the second: solid blocks of each colour where a warp block crosses a weft
// block of its own colour, shot blocks where they differ). Each colour is a
// yarn entry of its own, with its own curve file. With --dye-length L
// instead, every yarn is space-dyed: one yarn entry whose colour alternates
// between the two every L yarn radii of arc length along each curve
// (a colour per curve point in colours.txt, the scene's "vertex_colours").
// Parameters (SceneOptions, flags of `weft scene`): the model file (must
// load), N (--size), the yarn radius R, plies, ply twist, film size, spp and
// an optional environment map. Scene units: the world of docs/scene-format.md
// (+y up); every patch lies in the xy plane and faces +z, where the camera is.
#pragma once

#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "weft/core/curves.h"
#include "weft/core/family_box.h"
#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/render/scene_file.h"

namespace weft::eval {

enum class SceneKind { Closeup, Weave, Knit, Curves };

// "closeup", "weave", "knit", "curves".
const char* sceneKindName(SceneKind kind);
// The inverse; InputError naming `name` and the allowed kinds otherwise.
SceneKind parseSceneKind(const std::string& name);

// Allowed ranges, checked by SceneOptions::validate (each InputError names the
// flag and its range).
inline constexpr int kMaxPatchSize = 100;
inline constexpr double kMinRadius = 1e-6, kMaxRadius = 1e3;
inline constexpr double kMinDyeLength = 0.5, kMaxDyeLength = 1e4;
// Film shapes the generators frame (each generator checks them after
// validate; an InputError names --width, --height and the limit): at most
// kMaxFilmAspect times as wide as tall, since the yarns must run on past a
// wider view (over 175 degrees across) by hundreds of radii to keep their
// ends out of it; and a weave or knit at most kMaxPatchFilmTallness times as
// tall as wide, since a patch is seen from 19 degrees above and from 10.7
// times as tall the bottom of the view runs parallel to the cloth or past it,
// which no extension of the yarns fills. (A close-up may be any taller.)
inline constexpr double kMaxFilmAspect = 100;
inline constexpr double kMaxPatchFilmTallness = 10;
// The most yarn extensions (extendEndsOutOfView in scene_gen.cpp) a scene
// may need; the film shapes above need at most about half of it.
inline constexpr int kMaxEndMargin = 512;
inline constexpr int kDefaultStripe = 2;
// The vertex colour file of a space-dyed scene.
inline constexpr const char* kVertexColourFile = "colours.txt";

// The yarns' colours as SceneOptions::validate() resolves them.
struct SceneColours {
    // The fiber colours C_TT: --colours, or the C_TT of each --appearance
    // (the model's appearance table).
    std::vector<Rgb> fiber;
    // What a neural render of the scene would refuse about --colours (a
    // model of one colour, a colour outside the model's colour range): the
    // warnings weft scene prints (fiber and dual mode take any colour).
    std::vector<std::string> neuralWarnings;
};

// Where `weft scene curves` puts the camera (docs/scenes.md, "Your own
// curves"): in front (+z looking along -z), above (+y looking down, the
// image's up -z) or three-quarter (35 degrees to the right of the front and
// 30 above it).
enum class CurvesView { ThreeQuarter, Front, Top };
const char* curvesViewName(CurvesView view);
// The inverse; InputError naming --view and the allowed names otherwise.
CurvesView parseCurvesView(const std::string& name);

struct SceneOptions {
    std::string model;         // --model: MODEL.json from `weft fit`; must exist and load
    // --yarn: with a family model (weft fit family), the yarn every entry
    // draws (its parameters in the scene's "yarn"); refused with any other.
    std::optional<YarnPoint> yarn;
    int size = 6;              // --size N: weave N x N yarns, knit N courses x N loops; [1, 100]
    double radius = 0.01;      // --radius: yarn radius R in scene units; [1e-6, 1e3]
    int plies = 3;             // --plies: plies per yarn; [1, 16]
    double plyTwist = 0.3;     // --ply-twist: as the scene file's ply_twist; [-100, 100]
    int width = 512;           // --width: film width in pixels; [1, 16384]
    int height = 512;          // --height: film height in pixels; [1, 16384]
    int spp = 64;              // --spp: the scene's render.spp; [1, 1048576]
    std::string envmap;        // --envmap: .exr or .hdr lat-long map instead of the sky; "" = sky
    std::vector<Rgb> colours;  // --colours: none (the model's own), one or two C_TT, [0, 1]
    // --appearance: instead of --colours, one or two colours the yarns should
    // look (sRGB, [0, 1]; docs/colour.md, "Colour by appearance"), written as
    // the yarns' "appearance" (space-dyed: as the C_TT that gives them).
    std::vector<Rgb> appearances;
    // --stripe: courses (knit) or yarns (weave) per stripe, [1, 100]; only with
    // two colours and no dyeLength; unset: kDefaultStripe.
    std::optional<int> stripe;
    // --dye-length: space-dyed stretches in radii, [0.5, 10000] whenever given
    // (0 included: unset means no space dyeing); only with two colours.
    std::optional<double> dyeLength;
    // The curves kind: the curve file (.bcc, .txt, .obj), the view, and the
    // yarn radius in the file's units (--radius for that kind; unset: the
    // curve report's largest radius without overlap). The scene is written
    // in scene units where the yarn radius is `radius` (0.01).
    std::string curves;
    CurvesView view = CurvesView::ThreeQuarter;
    std::optional<double> curveRadius;
    // --floor: a diffuse grey (0.5) rectangle under the cloth (curves: below
    // its lowest point, normal +y) or behind it (the other kinds: the patch
    // faces +z, so behind its back, normal +z), 20 times the cloth's size.
    bool floor = false;

    // Range checks and the flags' combinations, then the model is loaded
    // (loadYarnModel, once) and the envmap checked for its extension and
    // readability; --appearance needs a colour model and each colour within
    // its reach; InputError naming the flag. Returns the yarns' colours.
    SceneColours validate() const;
    // The number of colours given (--colours or --appearance): 0, 1 or 2.
    size_t colourCount() const { return std::max(colours.size(), appearances.size()); }
    int stripeWidth() const { return stripe.value_or(kDefaultStripe); }
};

struct GeneratedScene {
    // One yarn entry per colour: yarns[i].curves is yarnCurveFile(i, count)
    // (relative: the folder writeScene writes); the model and envmap paths are
    // absolute. path and baseDir are empty.
    render::SceneDesc scene;
    CurveSet curves;  // every yarn centre line in scene units: open polylines
    // The yarn entry of each curve (curves.curves.size() entries, each in
    // [0, scene.yarns.size())).
    std::vector<int> entryOfCurve;
    // How far the yarns were extended to keep their ends out of view
    // (radii for the close-up, yarns and spacings for the weave, courses and
    // loops for the knit; docs/scenes.md), in [0, kMaxEndMargin].
    int endMargin = 0;
    // SceneColours::neuralWarnings of the options it was made with.
    std::vector<std::string> colourWarnings;
    // The curves kind: the yarn radius in the file's units, where it came
    // from ("given" or "largest_without_overlap"), and the scale from file
    // units to scene units (radius / curveRadius); 0 for the other kinds.
    double curveRadius = 0, curveScale = 0;
    std::string curveRadiusSource;
};

// "yarns.txt" for a scene with one yarn entry, else "yarns-1.txt", "yarns-2.txt", ...
// (".bcc" for the curves kind, which keeps a Catmull-Rom file's basis).
std::string yarnCurveFile(int entry, int entryCount, const std::string& extension = ".txt");
// The curves of each yarn entry, in entry order (the sets writeScene writes).
std::vector<CurveSet> entryCurves(const GeneratedScene& generated);

// Each validates `options` first.
GeneratedScene closeupScene(const SceneOptions& options);
GeneratedScene weaveScene(const SceneOptions& options);
GeneratedScene knitScene(const SceneOptions& options);
// Any curve file framed whole (docs/scenes.md, "Your own curves"): the
// curves scaled so that their radius (given, or the largest without overlap)
// becomes options.radius, a camera from options.view at the smallest distance
// that keeps every curve (padded by the radius) within kCurvesFill of the
// film, the paper's lights around it. Two colours alternate every --stripe
// curves, or along each curve with --dye-length. InputError naming the file
// when the curves touch or cross (largest radius 0: which curves, where, and
// whether a closed curve's closing segment does it) and no radius is given.
GeneratedScene curvesScene(const SceneOptions& options);
inline constexpr double kCurvesFill = 0.9;
// A curve set without contact pairs (largest radius unbounded) gets a yarn
// radius of this share of its box's diagonal.
inline constexpr double kNoContactRadiusFraction = 0.01;
GeneratedScene generateScene(SceneKind kind, const SceneOptions& options);

// Plain weave: warp j is (x, j d, (-1)^j A cos(pi x / d)), weft i is
// (i d, y, -(-1)^i A cos(pi y / d)). Crossing centre lines are 2 A apart and
// that is their minimum distance iff d >= pi sqrt(2) A (docs/scenes.md); we
// take A = R (1 + kWeaveClearance) and d = pi sqrt(2) A, the densest such weave.
inline constexpr double kWeaveClearance = 0.01;
inline constexpr int kWeaveSamplesPerSpacing = 32;
struct WeaveGeometry {
    double spacing = 0;    // d: distance between neighbouring parallel yarns
    double amplitude = 0;  // A: crimp amplitude in z
};
WeaveGeometry weaveGeometry(double radius);

// Crane's plain-knit curve in its own units (loop period 2 pi along x), with
// his parameters a = 3/2, h = 4, d = 1 and row spacing w = h + 1/2, scaled so
// that his units' yarn radius kKnitUnitRadius becomes R. With 0.75 (Crane
// draws 0.5) neighbouring courses come within 1.02 (2 R) of each other and the
// curve itself, between points more than pi R apart along it, within 1.03
// (2 R): they touch without intersecting (docs/scenes.md).
inline constexpr double kKnitUnitRadius = 0.75;
inline constexpr int kKnitSamplesPerLoop = 96;
struct KnitGeometry {
    double scale = 0;  // scene units per Crane unit: R / kKnitUnitRadius
    double roundness = 1.5, height = 4, depth = 1, rowSpacing = 4.5;  // a, h, d, w (Crane units)
};
KnitGeometry knitGeometry(double radius);
// Point of course `row` at parameter t (one loop per 2 pi), in scene units.
Vec3 knitPoint(const KnitGeometry& g, int row, double t);

// A camera at `box`'s centre minus D * forward, looking at the centre, with
// `up`: the smallest D for which every corner of the box projects
// within `fill` (0 < fill <= 1) of the film's half-width and half-height, so
// the whole box is in view (the view frustum is convex).
render::CameraDesc frameBox(const Bounds3& box, const Vec3& forward, double fovDeg, int width,
                            int height, double fill, const Vec3& up = {0, 1, 0});

// A camera looking along `forward` (up (0, 1, 0)) at the centre of the
// rectangle [x0, x1] x [y0, y1] of the plane z = 0, as far away as it can be
// while the rays through the four film corners still land in the rectangle:
// the rectangle covers the whole film (the cloth fills the frame).
render::CameraDesc frameCover(double x0, double x1, double y0, double y1, const Vec3& forward,
                              double fovDeg, int width, int height);

// True when the ball of radius `radius` around p is entirely out of the view
// of `camera` on a width x height film (beyond one side of the frustum).
bool outOfView(const render::CameraDesc& camera, int width, int height, const Vec3& p,
               double radius);

// Writes the curve files (yarnCurveFile; docs/curves.md text format) and
// DIR/scene.json (docs/scene-format.md) as one atomic directory
// (TempDirCommit). An existing DIR is replaced only when it holds nothing but
// files of an earlier scene (scene.json, yarns.txt, yarns-N.txt); otherwise
// InputError naming DIR and the first other entry.
void writeScene(const GeneratedScene& generated, const std::string& dir);

// What `weft scene` reports of `generated` written to `dir` (one JSON line on
// stdout): kind, scene, curves (one file per yarn entry), colours, yarns
// (curve count), points, radius and yarn_overlap, the overlap check that
// `weft render` runs at load (render::checkYarnOverlap); the warnings of
// overlapping entries go to `warnings`.
nlohmann::json sceneSummary(const GeneratedScene& generated, SceneKind kind, const std::string& dir,
                            std::vector<std::string>* warnings);

// The curves' colours as a vertex colour file (docs/scene-format.md):
// "r g b" per point (%.9g), a blank line between curves.
std::string vertexColoursText(const CurveSet& curves);

// The curves as the text that writeScene writes ("x y z" lines, %.9g).
std::string curvesText(const CurveSet& curves);

}  // namespace weft::eval
