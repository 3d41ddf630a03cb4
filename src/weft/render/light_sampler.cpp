#include "weft/render/light_sampler.h"

#include <algorithm>
#include <cmath>

#include "weft/core/error.h"

namespace weft::render {

nlohmann::json LightSamplerDesc::toJson() const {
    switch (kind) {
        case LightSamplerKind::Uniform:
            return "uniform";
        case LightSamplerKind::Power:
            return "power";
        case LightSamplerKind::Weights:
            return {{"weights", weights}};
    }
    return "uniform";
}

LightSamplerDesc LightSamplerDesc::read(const JsonObjectReader& scene, size_t lights) {
    LightSamplerDesc d;
    const nlohmann::json& v = scene.value("light_sampler");
    if (v.is_string()) {
        d.kind = static_cast<LightSamplerKind>(scene.oneOf("light_sampler", {"uniform", "power"}));
        return d;
    }
    if (!v.is_object())
        scene.fail("light_sampler",
                   "expected \"uniform\", \"power\" or {\"weights\": [one per light]}");
    const JsonObjectReader w = scene.object("light_sampler", {"weights"});
    // A scene without lights has the procedural sky: one light.
    const size_t n = std::max<size_t>(lights, 1);
    d.kind = LightSamplerKind::Weights;
    d.weights = w.numbers("weights", n, NumberRange::atLeast(0),
                          lights == 0 ? "(one per light: none given, the procedural sky)"
                                      : "(one per light of the scene)");
    double sum = 0;
    for (double x : d.weights) sum += x;
    if (!(sum > 0)) w.fail("weights", "at least one weight must be > 0");
    return d;
}

LightSampler::LightSampler(size_t n) : pmf_(n, n > 0 ? 1.0 / static_cast<double>(n) : 0.0) {}

LightSampler::LightSampler(const std::vector<double>& weights) {
    double sum = 0;
    for (double w : weights) {
        if (!std::isfinite(w) || w < 0)
            throw InputError("light sampler: a weight is not finite and >= 0");
        sum += w;
    }
    if (!(sum > 0)) {
        *this = LightSampler(weights.size());
        return;
    }
    uniform_ = false;
    pmf_.resize(weights.size());
    cdf_.resize(weights.size());
    double running = 0;
    for (size_t i = 0; i < weights.size(); ++i) {
        pmf_[i] = weights[i] / sum;
        running += pmf_[i];
        cdf_[i] = running;
    }
    cdf_.back() = 1.0;
}

int LightSampler::sample(double u, double* pmf) const {
    const int n = static_cast<int>(pmf_.size());
    int i;
    if (uniform_) {
        i = std::min(static_cast<int>(u * n), n - 1);
    } else {
        // The first light whose cumulative probability exceeds u: a light of
        // probability 0 shares its predecessor's and is never the first.
        i = static_cast<int>(std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin());
        i = std::min(i, n - 1);
    }
    *pmf = pmf_[i];
    return i;
}

}  // namespace weft::render
