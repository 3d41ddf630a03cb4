#include "weft/yarn/network.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "weft/core/error.h"
#include "weft/core/rng.h"

namespace weft {

std::string toString(OutputFunction f) {
    switch (f) {
        case OutputFunction::Identity:
            return "identity";
        case OutputFunction::Sigmoid:
            return "sigmoid";
        case OutputFunction::Exp:
            return "exp";
    }
    return "identity";
}

std::vector<int> NetworkWeights::widths() const {
    std::vector<int> w;
    if (layers.empty()) return w;
    w.push_back(layers.front().in);
    for (const NetworkLayer& l : layers) w.push_back(l.out);
    return w;
}

std::string NetworkWeights::widthsText() const {
    std::string text;
    for (int w : widths()) {
        if (!text.empty()) text += '-';
        text += std::to_string(w);
    }
    return text;
}

size_t NetworkWeights::parameterCount() const {
    size_t n = 0;
    for (const NetworkLayer& l : layers) n += l.weight.size() + l.bias.size() + l.prelu.size();
    return n;
}

void NetworkWeights::validate(const std::string& name, int in, int out, OutputFunction required,
                              const char* why) const {
    if (layers.empty()) throw InputError(name + ": the network has no layers");
    if (inputs() != in || outputs() != out)
        throw InputError(name + ": expected " + std::to_string(in) + " inputs and " +
                         std::to_string(out) + " output" + (out == 1 ? "" : "s") + ", got " +
                         widthsText());
    for (size_t l = 0; l < layers.size(); ++l) {
        const NetworkLayer& layer = layers[l];
        const std::string at = name + ".layers[" + std::to_string(l) + "]";
        if (l > 0 && layer.in != layers[l - 1].out)
            throw InputError(at + ": " + std::to_string(layer.in) + " inputs after a layer of " +
                             std::to_string(layers[l - 1].out) + " outputs");
        if (layer.in < 1 || layer.out < 1 ||
            layer.weight.size() != static_cast<size_t>(layer.in) * layer.out ||
            layer.bias.size() != static_cast<size_t>(layer.out) ||
            (layer.hasPrelu() && layer.prelu.size() != static_cast<size_t>(layer.out)))
            throw InputError(at + ": weight, bias or prelu sizes do not match its " +
                             std::to_string(layer.out) + " x " + std::to_string(layer.in) +
                             " shape");
    }
    if (output != required)
        throw InputError(name + ".output: the yarn BSDF needs \"" + toString(required) + "\" (" +
                         why + "), got \"" + toString(output) + "\"");
}

void NetworkWeights::checkFiniteOnUnitInputs(const std::string& name) const {
    // The inputs are unit-vector components (|x| <= 1), so |z_o| <= |b_o| +
    // sum_j |w_oj| bound_j layer by layer (a PReLU scales by at most
    // max(1, |a|)). Far below float's 3.4e38, no input can make the float
    // inference overflow.
    constexpr double kMaxActivation = 1e30;
    std::vector<double> bound(static_cast<size_t>(inputs()), 1.0), next;
    for (size_t l = 0; l < layers.size(); ++l) {
        const NetworkLayer& layer = layers[l];
        next.assign(static_cast<size_t>(layer.out), 0.0);
        for (int o = 0; o < layer.out; ++o) {
            double z = std::fabs(layer.bias[o]);
            for (int j = 0; j < layer.in; ++j) z += std::fabs(layer.w(o, j)) * bound[j];
            if (layer.hasPrelu())
                z *= std::max(1.0, std::fabs(static_cast<double>(layer.prelu[o])));
            if (!(z <= kMaxActivation)) {
                char text[32];
                std::snprintf(text, sizeof text, "%.3g", z);
                throw InputError(name + ".layers[" + std::to_string(l) + "]: output " +
                                 std::to_string(o) + " can reach " + text +
                                 " for unit-vector inputs (weights, biases or PReLU slopes too "
                                 "large): allowed at most 1e30, where float inference stays "
                                 "finite");
            }
            next[o] = z;
        }
        bound.swap(next);
    }
}

NetworkWeights NetworkWeights::initialised(const std::vector<int>& widths,
                                           const std::vector<bool>& prelu, OutputFunction output,
                                           uint64_t seed) {
    if (widths.size() < 2)
        throw InputError("a network needs at least an input and an output width");
    if (prelu.size() + 1 != widths.size())
        throw std::invalid_argument("NetworkWeights: one PReLU flag per layer expected");
    for (int w : widths)
        if (w < 1 || w > 4096)
            throw InputError("layer width " + std::to_string(w) +
                             " is out of range: allowed [1, 4096]");
    NetworkWeights net;
    net.output = output;
    Rng rng(0x4d4c50, seed);
    for (size_t l = 0; l + 1 < widths.size(); ++l) {
        NetworkLayer layer;
        layer.in = widths[l];
        layer.out = widths[l + 1];
        const double bound = 1.0 / std::sqrt(static_cast<double>(layer.in));
        // One stream, weights (row-major) then biases, layer after layer.
        layer.weight.resize(static_cast<size_t>(layer.in) * layer.out);
        for (float& w : layer.weight) w = static_cast<float>(bound * (2.0 * rng.uniform() - 1.0));
        layer.bias.resize(static_cast<size_t>(layer.out));
        for (float& b : layer.bias) b = static_cast<float>(bound * (2.0 * rng.uniform() - 1.0));
        if (prelu[l]) layer.prelu.assign(static_cast<size_t>(layer.out), 0.25f);
        net.layers.push_back(std::move(layer));
    }
    return net;
}

NetworkWeights NetworkWeights::initialised(const std::vector<int>& widths, OutputFunction output,
                                           uint64_t seed) {
    std::vector<bool> prelu(widths.size() < 2 ? 0 : widths.size() - 1, true);
    if (!prelu.empty()) prelu.back() = false;
    return initialised(widths, prelu, output, seed);
}

NetworkWeights foldConstantInputs(const NetworkWeights& net, int keep,
                                  const std::vector<double>& constants) {
    if (net.layers.empty() || keep < 1 || keep + static_cast<int>(constants.size()) != net.inputs())
        throw std::logic_error("foldConstantInputs: " + std::to_string(keep) + " inputs kept and " +
                               std::to_string(constants.size()) + " constants for a network of " +
                               std::to_string(net.inputs()) + " inputs");
    NetworkWeights folded = net;
    const NetworkLayer& first = net.layers.front();
    NetworkLayer& layer = folded.layers.front();
    layer.in = keep;
    layer.weight.resize(static_cast<size_t>(keep) * first.out);
    for (int o = 0; o < first.out; ++o) {
        double bias = first.bias[o];
        for (size_t j = 0; j < constants.size(); ++j)
            bias += static_cast<double>(first.w(o, keep + static_cast<int>(j))) * constants[j];
        layer.bias[o] = static_cast<float>(bias);
        for (int j = 0; j < keep; ++j)
            layer.weight[static_cast<size_t>(o) * keep + j] = first.w(o, j);
    }
    return folded;
}

}  // namespace weft
