#include "weft/yarn/yarn_sampler.h"

#include "weft/core/error.h"
#include "weft/yarn/cosine_sampler.h"
#include "weft/yarn/fitted_sampler.h"
#include "weft/yarn/tabulated_sampler.h"

namespace weft {

YarnSampling parseYarnSampling(const std::string& name, const std::string& what) {
    if (name == "tabulated") return YarnSampling::Tabulated;
    if (name == "fitted") return YarnSampling::Fitted;
    if (name == "cosine") return YarnSampling::Cosine;
    throw InputError(what + " \"" + name +
                     "\": unknown yarn sampling (allowed: tabulated, fitted, cosine)");
}

const char* yarnSamplingName(YarnSampling sampling) {
    switch (sampling) {
        case YarnSampling::Tabulated:
            return "tabulated";
        case YarnSampling::Fitted:
            return "fitted";
        case YarnSampling::Cosine:
            return "cosine";
    }
    return "fitted";
}

std::unique_ptr<const YarnSampler> makeYarnSampler(
    YarnSampling kind, const YarnModel& model, const std::shared_ptr<const YarnEvaluator>& evaluator) {
    switch (kind) {
        case YarnSampling::Tabulated:
            return std::make_unique<TabulatedYarnSampler>(evaluator);
        case YarnSampling::Fitted:
            return std::make_unique<FittedYarnSampler>(model, *evaluator);
        case YarnSampling::Cosine:
            return std::make_unique<CosineYarnSampler>();
    }
    throw std::logic_error("unknown yarn sampling");
}

}  // namespace weft
