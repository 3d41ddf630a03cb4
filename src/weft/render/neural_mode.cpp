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
    // The draft samples by the fitted lobes (paper eq. 9-11) instead of the
    // table, whose build is about half of the BSDF's; finishing builds the
    // table from the draft's own evaluator.
    std::unique_ptr<Bsdf> makeDraftBsdf(const YarnModel& model, const std::optional<Rgb>& colour,
                                        const std::string& source, const std::string& what,
                                        const YarnBsdfOptions& yarn) const override {
        YarnBsdfOptions draft = yarn;
        if (draft.sampling == YarnSampling::Tabulated) draft.sampling = YarnSampling::Fitted;
        return makeBsdf(model, colour, source, what, draft);
    }
    std::unique_ptr<Bsdf> finishDraft(const Bsdf& draft,
                                      const YarnBsdfOptions& yarn) const override {
        const auto& bsdf = static_cast<const YarnBsdf&>(draft);  // makeBsdf's kind
        if (bsdf.sampling() == yarn.sampling) return nullptr;
        return bsdf.withTabulatedSampling();
    }
};

}  // namespace

const YarnMode& neuralYarnMode() {
    static const NeuralYarnMode mode;
    return mode;
}

}  // namespace weft::render
