// weft/yarn/network.h — the weights of the yarn model's small networks, as plain data.
//
// Paper 5.2-5.3, docs/design.md 6: fully connected layers y = W x + b, a
// channel-wise PReLU y = max(z, 0) + a min(z, 0) after every hidden layer, and
// an output function on the last layer: sigmoid (T network, P(T | wi)) or exp
// (M network, RGB radiance). NetworkWeights is what model.json stores
// (yarn_model.h) and what both the renderer's float inference (FixedMlp,
// fixed_mlp.h) and the trainer's Mlp (fit/mlp.h) are built from, so the
// runtime never depends on the trainer. Parameters are float32, as trained.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace weft {

enum class OutputFunction { Identity, Sigmoid, Exp };

std::string toString(OutputFunction f);

struct NetworkLayer {
    int in = 0, out = 0;
    std::vector<float> weight;  // out x in, row-major: weight[o * in + j]
    std::vector<float> bias;    // out
    std::vector<float> prelu;   // out slopes, or empty: no PReLU after this layer

    bool hasPrelu() const { return !prelu.empty(); }
    float w(int o, int j) const { return weight[static_cast<size_t>(o) * in + j]; }
    bool operator==(const NetworkLayer&) const = default;
};

struct NetworkWeights {
    std::vector<NetworkLayer> layers;
    OutputFunction output = OutputFunction::Identity;

    bool operator==(const NetworkWeights&) const = default;
    int inputs() const { return layers.empty() ? 0 : layers.front().in; }
    int outputs() const { return layers.empty() ? 0 : layers.back().out; }
    // {inputs, hidden widths..., outputs}; "6-21-21-21-3" as text.
    std::vector<int> widths() const;
    std::string widthsText() const;
    size_t parameterCount() const;

    // InputError starting with `name` ("t_net") unless the network has layers,
    // `inputs` inputs, `outputs` outputs, consistent layer shapes and vector
    // sizes, and the output function `output` (`why` says what needs it).
    void validate(const std::string& name, int inputs, int outputs, OutputFunction output,
                  const char* why) const;
    // InputError starting with `name` unless every value inside the network
    // stays within 1e30 for any inputs in [-1, 1] (a bound from the weights'
    // magnitudes), so that float inference cannot overflow whatever the
    // direction. The file format holds any float; the runtime BSDF
    // (yarn_bsdf.h) refuses networks that fail this.
    void checkFiniteOnUnitInputs(const std::string& name) const;

    // The trainer's initialisation (PyTorch's Linear default): weights and
    // biases U(-1/sqrt(in), 1/sqrt(in)), PReLU slopes 0.25, from `seed`;
    // `prelu` has one flag per layer (widths.size() - 1). InputError for fewer
    // than two widths or a width outside [1, 4096].
    static NetworkWeights initialised(const std::vector<int>& widths,
                                      const std::vector<bool>& prelu, OutputFunction output,
                                      uint64_t seed);
    // The same with a PReLU after every hidden layer (the paper's networks).
    static NetworkWeights initialised(const std::vector<int>& widths, OutputFunction output,
                                      uint64_t seed);
};

// `net` with its inputs from `keep` on held at `constants` (one per such
// input, in order): their columns of the first layer are folded into its
// bias (in double, rounded once to float), so the result has `keep` inputs
// and, for every input, the output `net` has with those constants. A family
// model (family_model.h) becomes an ordinary model of one yarn this way.
NetworkWeights foldConstantInputs(const NetworkWeights& net, int keep,
                                  const std::vector<double>& constants);

}  // namespace weft
