// weft/yarn/network_capacity.h — the largest T and M networks the renderer runs.
//
// The renderer evaluates the yarn model's networks with FixedMlp
// (fixed_mlp.h), whose storage is fixed at compile time: a widest layer, a
// number of layers, and a number of floats after padding. This header is
// the one place those limits live. fixed_mlp.h builds TransmissionMlp and
// ScatteringMlp from them, and weft fit checks its configured architectures
// against them before it trains (FitConfig::validate, fit_config.h), so that
// a fit never spends minutes on a network that `weft render` then refuses.
//
// A colour-conditioned M network (colour_basis.h) has 3K outputs while it is
// trained, but the renderer runs it folded to 3 outputs
// (foldColourIntoNetwork): its hidden layers are checked as M's.
#pragma once

#include <string>
#include <vector>

namespace weft {

// Floats per vector of the widest kernel (AVX-512). Parameter counts pad every
// layer's outputs to it, whatever the kernel this CPU runs, so that whether a
// network fits does not depend on the machine.
inline constexpr int kNetworkPaddingLanes = 16;
// Layers a FixedMlp holds: the hidden layers plus the output layer.
inline constexpr int kMaxNetworkLayers = 8;

struct NetworkCapacity {
    const char* name;  // "T" or "M", as docs/design.md 6 names the networks
    int inputs;        // 3 (wi) or 6 (wi, wo)
    int outputs;       // 1 (P(T | wi)) or 3 (RGB)
    int maxWidth;      // the widest layer
    int maxLayers;     // layers in all, the output layer included
    int floats;        // weights, biases and PReLU slopes after padding (paddedLayerFloats)
};

// The renderer's T network (TransmissionMlp) and M network (ScatteringMlp).
inline constexpr NetworkCapacity kTransmissionCapacity{"T", 3, 1, 32, kMaxNetworkLayers, 2048};
inline constexpr NetworkCapacity kScatteringCapacity{"M", 6, 3, 64, kMaxNetworkLayers, 8192};

// Floats that a layer of `in` inputs and `out` outputs takes in a FixedMlp:
// `in` columns of weights, a bias and, after a hidden layer, a PReLU slope per
// output, with the outputs padded with zeros to a multiple of `lanes`.
constexpr long long paddedLayerFloats(int in, int out, bool prelu,
                                      int lanes = kNetworkPaddingLanes) {
    return static_cast<long long>((out + lanes - 1) / lanes * lanes) * (in + 1 + (prelu ? 1 : 0));
}

// The floats of the network capacity.inputs -> hidden... -> capacity.outputs
// with a PReLU after every hidden layer, as weft fit trains it.
long long paddedParameterCount(const std::vector<int>& hidden, const NetworkCapacity& capacity);

// InputError "<field> = [w1, w2, ...] is out of range: the renderer's M
// network holds ..." (naming the limit and this header) unless every width is
// in [1, maxWidth], there are at most maxLayers - 1 hidden layers, and the
// network's padded parameters fit in capacity.floats. `field` names where the
// widths came from ("fit.json: m_net.hidden").
void checkHiddenWidths(const std::vector<int>& hidden, const NetworkCapacity& capacity,
                       const std::string& field);

}  // namespace weft
