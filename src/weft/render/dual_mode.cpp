// The dual drawing mode (yarn_mode.h): each ply as one curve, shaded with the
// dual-scattering baseline after ZMA23 (yarn/dual_scattering.h,
// docs/dual-scattering.md), computed from the model's fiber and ply alone.
#include "weft/render/yarn_mode.h"
#include "weft/yarn/dual_scattering.h"

namespace weft::render {

namespace {

class DualYarnMode final : public YarnMode {
  public:
    const char* name() const override { return "dual"; }
    bool drawsPlies() const override { return true; }
    std::unique_ptr<Bsdf> makeBsdf(const YarnModel& model, const std::optional<Rgb>& colour,
                                   const std::string&, const std::string&,
                                   const YarnBsdfOptions&) const override {
        return std::make_unique<DualScatteringBsdf>(fiberInColour(model, colour), model.ply);
    }
};

}  // namespace

const YarnMode& dualYarnMode() {
    static const DualYarnMode mode;
    return mode;
}

}  // namespace weft::render
