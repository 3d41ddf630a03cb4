// The fiber drawing mode (yarn_mode.h): every fiber of each ply, shaded with
// the fiber BCSDF (Khungurn et al. 2015; fiber/fiber_bcsdf.h): the ground truth.
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/render/yarn_mode.h"

namespace weft::render {

namespace {

class FiberYarnMode final : public YarnMode {
  public:
    const char* name() const override { return "fiber"; }
    bool drawsPlies() const override { return false; }
    std::unique_ptr<Bsdf> makeBsdf(const YarnModel& model, const std::optional<Rgb>& colour,
                                   const std::string&, const std::string&,
                                   const YarnBsdfOptions&) const override {
        return std::make_unique<FiberBcsdf>(fiberInColour(model, colour));
    }
};

}  // namespace

const YarnMode& fiberYarnMode() {
    static const FiberYarnMode mode;
    return mode;
}

}  // namespace weft::render
