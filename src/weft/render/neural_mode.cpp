// The neural drawing mode (yarn_mode.h): each ply as one curve, shaded with
// the fitted yarn BSDF of its model (paper 4; yarn/yarn_bsdf.h).
#include "weft/render/yarn_mode.h"

namespace weft::render {

namespace {

class NeuralYarnMode final : public YarnMode {
  public:
    const char* name() const override { return "neural"; }
    bool drawsPlies() const override { return true; }
    std::unique_ptr<Bsdf> makeBsdf(const YarnModel& model, const std::optional<Rgb>& colour,
                                   const std::string& source, const std::string& what,
                                   const YarnBsdfOptions& yarn) const override {
        // Another colour needs a colour-conditioned model (docs/colour.md).
        return std::make_unique<YarnBsdf>(colour ? model.forColour(*colour, what) : model, source,
                                          yarn);
    }
};

}  // namespace

const YarnMode& neuralYarnMode() {
    static const NeuralYarnMode mode;
    return mode;
}

}  // namespace weft::render
