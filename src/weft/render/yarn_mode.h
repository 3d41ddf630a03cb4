// weft/render/yarn_mode.h — how a yarn of a scene is drawn and shaded.
//
// A drawing mode decides the geometry of a yarn (each ply as one curve, or
// every fiber of it) and the BSDF its materials get. Three are registered
// (yarn_modes.cpp), each in its own file:
//   neural  plies as curves, the fitted yarn BSDF (yarn/yarn_bsdf.h);
//   dual    plies as curves, the dual-scattering baseline after ZMA23
//           (yarn/dual_scattering.h), from the model's fiber and ply;
//   fiber   every fiber of each ply (N, rho, alpha of the model's "ply"), the
//           fiber BCSDF: the ground truth.
// A scene's yarn names its mode ("mode", scene_file.h; neural when absent)
// and `weft render --mode` overrides every yarn's, so one scene may mix them.
// A new mode is one file (a YarnMode and the function that returns it) and
// its line in yarn_modes.cpp.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "weft/core/bsdf.h"
#include "weft/core/json_reader.h"
#include "weft/core/rgb.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_model.h"

namespace weft::render {

class YarnMode {
  public:
    virtual ~YarnMode() = default;

    virtual const char* name() const = 0;
    // Whether each ply is drawn as one curve, shaded in the yarn frame (t, t x
    // n, n) of docs/design.md 2; false: its fibers, each shaded in the fiber
    // frame (tangent +x, fiber/fiber_bcsdf.h).
    virtual bool drawsPlies() const = 0;
    // The BSDF of one material: `model` as its file `source` holds it, in
    // `colour` (a fiber C_TT; none: the model's own), with `what` naming the
    // colour's scene field in messages; `yarn` configures the neural yarn BSDF.
    virtual std::unique_ptr<Bsdf> makeBsdf(const YarnModel& model,
                                           const std::optional<Rgb>& colour,
                                           const std::string& source, const std::string& what,
                                           const YarnBsdfOptions& yarn) const = 0;
    // A viewport's quick first look (weft view, after a colour edit): a BSDF
    // with makeBsdf's values that builds faster, sampled more coarsely (so its
    // images are unbiased, only noisier), and the step that makes such a
    // draft makeBsdf's BSDF bit for bit (null when `draft` is final already).
    // Modes whose BSDF builds fast have no draft: makeBsdf's, already final.
    virtual std::unique_ptr<Bsdf> makeDraftBsdf(const YarnModel& model,
                                                const std::optional<Rgb>& colour,
                                                const std::string& source, const std::string& what,
                                                const YarnBsdfOptions& yarn) const {
        return makeBsdf(model, colour, source, what, yarn);
    }
    virtual std::unique_ptr<Bsdf> finishDraft(const Bsdf& /*draft*/,
                                              const YarnBsdfOptions& /*yarn*/) const {
        return nullptr;
    }
};

// The model's fiber in `colour` (none: its own C_TT): the fiber-level modes
// take any colour with any model, so a ground truth exists for every colour.
inline FiberParams fiberInColour(const YarnModel& model, const std::optional<Rgb>& colour) {
    FiberParams fiber = model.fiber;
    if (colour) fiber.cTT = *colour;
    return fiber;
}

// Every registered mode, in the order messages list them.
const std::vector<const YarnMode*>& yarnModes();
// The mode of that name; InputError "<field> "<name>" is not a render mode:
// allowed neural, fiber, dual" otherwise.
const YarnMode& yarnModeNamed(const std::string& name, const std::string& field = "--mode");
// The mode of a yarn that names none.
const YarnMode& defaultYarnMode();
// A scene key holding a registered mode's name (InputError through r otherwise).
std::string readYarnModeName(const JsonObjectReader& r, std::string_view key);

}  // namespace weft::render
