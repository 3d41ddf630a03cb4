// weft/render/light_sampler.h — which light next-event estimation samples
// (issue 45, docs/scene-format.md "Light sampler").
//
// A scene's "light_sampler" picks one light per shading point for NEE with
// probability p_i, and the path tracer's MIS weights use the same p_i
// (path_tracer.h): the estimator stays unbiased for any p_i, and a light with
// p_i = 0 is reached by BSDF sampling alone, at full weight.
//   "uniform"   p_i = 1 / n (the default: the images weft rendered before)
//   "power"     p_i proportional to each light's power (Light::power, pbrt's
//               Phi): many dim lights cost little, one bright light gets the
//               samples
//   {"weights": [w_0, ..., w_{n-1}]}  p_i = w_i / sum w (each finite, >= 0,
//               sum > 0), one per light of the scene
// A scene whose lights all have zero power falls back to uniform.
#pragma once

#include <string>
#include <vector>

#include "weft/core/json_reader.h"

namespace weft::render {

enum class LightSamplerKind { Uniform, Power, Weights };

struct LightSamplerDesc {
    LightSamplerKind kind = LightSamplerKind::Uniform;
    std::vector<double> weights;  // Weights only

    bool isDefault() const { return kind == LightSamplerKind::Uniform; }
    // "uniform", "power" or {"weights": [...]}.
    nlohmann::json toJson() const;
    // The value of "light_sampler" in `scene`, for a scene of `lights`
    // lights: InputError naming the key and what is allowed.
    static LightSamplerDesc read(const JsonObjectReader& scene, size_t lights);
};

// A discrete distribution over a scene's lights.
class LightSampler {
  public:
    LightSampler() = default;
    // Uniform over n lights.
    explicit LightSampler(size_t n);
    // p_i proportional to weights[i] (finite, >= 0); uniform when they sum to 0.
    explicit LightSampler(const std::vector<double>& weights);

    size_t size() const { return pmf_.size(); }
    // The light for u in [0, 1), and its probability. Uniform: min(floor(u n),
    // n - 1), the pick of weft's renders before samplers.
    int sample(double u, double* pmf) const;
    double pmf(size_t light) const { return pmf_[light]; }

  private:
    bool uniform_ = true;
    std::vector<double> pmf_, cdf_;  // cdf_[i]: sum of pmf_[0..i]
};

}  // namespace weft::render
