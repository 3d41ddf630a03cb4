// weft/yarn/fixed_mlp.h — allocation-free inference of the yarn model's small networks.
//
// The renderer evaluates the T network (3-7-7-1) and the M network
// (6-21-21-21-3 by default) once per BSDF query, one direction pair at a
// time; Mlp<float>::forward (Eigen, whole batches, heap matrices) costs more
// than the rest of the BSDF there. FixedMlp copies the weights of a
// NetworkWeights (network.h) once into one contiguous std::array and evaluates the same
// function y = out(W_L ... prelu(W_1 x + b_1) ... + b_L) without touching the
// heap:
//   - widths are run-time values up to MaxWidth (the architecture is a fit
//     option, DESIGN.md 6), all parameters after padding fit in Capacity floats;
//   - each layer is stored column-major with its output count padded to a
//     multiple of kLanes (8) with zero weights; the layer kernel is compiled
//     for each padded width N, so y[0..N) += W[0..N, j] x[j] keeps its N
//     accumulators in registers as 4-wide SIMD multiply-adds (GCC / Clang
//     vector extensions); padded outputs stay 0;
//   - PReLU as max(z, 0) + slope min(z, 0): the same value, no branches;
//   - float arithmetic like the training code; only the summation order
//     differs from Eigen's (results agree to about 1e-6 relative);
//   - the exp output saturates at e^80 so that no input can give +inf.
// For the 6-21-21-21-3 network the weights take 6 KB: they stay in L1.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "weft/core/error.h"
#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/yarn/network.h"

namespace weft {

template <int MaxWidth, int Capacity>
class FixedMlp {
  public:
    static constexpr int kLanes = 8;
    static constexpr int kMaxLayers = 8;
    static_assert(MaxWidth % kLanes == 0, "MaxWidth must be a multiple of the SIMD block");

    FixedMlp() = default;

    // Copies `net`; InputError starting with `name` ("m_net") when it is wider,
    // deeper or larger than this evaluator supports.
    FixedMlp(const NetworkWeights& net, const std::string& name) : output_(net.output) {
        const auto& layers = net.layers;
        if (layers.empty() || layers.size() > static_cast<size_t>(kMaxLayers))
            throw InputError(name + ": " + std::to_string(layers.size()) +
                             " layers; the renderer's network evaluator supports 1 to " +
                             std::to_string(kMaxLayers));
        int offset = 0;
        layerCount_ = static_cast<int>(layers.size());
        for (int l = 0; l < layerCount_; ++l) {
            const NetworkLayer& src = layers[l];
            if (src.in > MaxWidth || src.out > MaxWidth)
                throw InputError(name + ": layers[" + std::to_string(l) + "] is " +
                                 std::to_string(src.out) + " x " + std::to_string(src.in) +
                                 "; the renderer's network evaluator supports widths up to " +
                                 std::to_string(MaxWidth));
            Layer& dst = layers_[l];
            dst.in = src.in;
            dst.out = src.out;
            dst.outPadded = (src.out + kLanes - 1) / kLanes * kLanes;
            dst.prelu = src.hasPrelu();
            dst.offset = offset;
            offset += dst.outPadded * (dst.in + 1 + (dst.prelu ? 1 : 0));
            if (offset > Capacity)
                throw InputError(name + ": " + std::to_string(net.parameterCount()) +
                                 " parameters need more than the " + std::to_string(Capacity) +
                                 " (after padding to blocks of " + std::to_string(kLanes) +
                                 ") that the renderer's network evaluator holds");
            float* p = params_.data() + dst.offset;
            for (int j = 0; j < dst.in; ++j)
                for (int o = 0; o < dst.out; ++o) p[j * dst.outPadded + o] = src.w(o, j);
            float* b = p + dst.in * dst.outPadded;
            for (int o = 0; o < dst.out; ++o) b[o] = src.bias[o];
            if (dst.prelu)
                for (int o = 0; o < dst.out; ++o) b[dst.outPadded + o] = src.prelu[o];
        }
    }

    int inputs() const { return layers_[0].in; }
    int outputs() const { return layerCount_ > 0 ? layers_[layerCount_ - 1].out : 0; }
    OutputFunction output() const { return output_; }

    // y[0, outputs()) = net(x[0, inputs())).
    void forward(const float* x, float* y) const {
        alignas(32) std::array<float, MaxWidth> bufferA, bufferB;
        float* a = bufferA.data();
        float* z = bufferB.data();
        for (int k = 0; k < layers_[0].in; ++k) a[k] = x[k];
        for (int l = 0; l < layerCount_; ++l) {
            const Layer& layer = layers_[l];
            dispatchLayer<kLanes>(layer, params_.data() + layer.offset, a, z);
            std::swap(a, z);
        }
        const int out = outputs();
        for (int o = 0; o < out; ++o) {
            switch (output_) {
                case OutputFunction::Sigmoid:
                    y[o] = 1.0f / (1.0f + std::exp(-a[o]));
                    break;
                case OutputFunction::Exp:
                    y[o] = std::exp(std::min(a[o], 80.0f));
                    break;
                case OutputFunction::Identity:
                    y[o] = a[o];
                    break;
            }
        }
    }

  private:
    struct Layer {
        int in = 0, out = 0, outPadded = 0, offset = 0;
        bool prelu = false;
    };

    // One layer of compile-time padded width N: the N accumulators are N / 4
    // four-float vectors (GCC / Clang vector extensions, SSE on x86-64, NEON
    // on ARM) kept in registers; every input adds N / 4 independent
    // multiply-adds. PReLU as max(z, 0) + slope min(z, 0): exact, branch-free.
    using Float4 = float __attribute__((vector_size(16)));
    template <int N>
    static void denseLayer(const Layer& layer, const float* w, const float* a, float* z) {
        constexpr int kVectors = N / 4;
        const float* bias = w + layer.in * N;
        Float4 acc[kVectors];
        for (int k = 0; k < kVectors; ++k) __builtin_memcpy(&acc[k], bias + 4 * k, sizeof(Float4));
        for (int j = 0; j < layer.in; ++j) {
            const Float4 x = {a[j], a[j], a[j], a[j]};
            const float* column = w + j * N;
            for (int k = 0; k < kVectors; ++k) {
                Float4 c;
                __builtin_memcpy(&c, column + 4 * k, sizeof(Float4));
                acc[k] += c * x;
            }
        }
        if (layer.prelu) {
            const float* slope = bias + N;
            const Float4 zero = {0, 0, 0, 0};
            for (int k = 0; k < kVectors; ++k) {
                Float4 s;
                __builtin_memcpy(&s, slope + 4 * k, sizeof(Float4));
                const Float4 positive = acc[k] > zero ? acc[k] : zero;
                const Float4 negative = acc[k] < zero ? acc[k] : zero;
                acc[k] = positive + s * negative;
            }
        }
        for (int k = 0; k < kVectors; ++k) __builtin_memcpy(z + 4 * k, &acc[k], sizeof(Float4));
    }

    template <int N>
    static void dispatchLayer(const Layer& layer, const float* w, const float* a, float* z) {
        if constexpr (N <= MaxWidth) {
            if (layer.outPadded == N) return denseLayer<N>(layer, w, a, z);
            dispatchLayer<N + kLanes>(layer, w, a, z);
        }
    }

    std::array<Layer, kMaxLayers> layers_{};
    int layerCount_ = 0;
    OutputFunction output_ = OutputFunction::Identity;
    alignas(32) std::array<float, Capacity> params_{};
};

// The yarn model's two evaluators (yarn_bsdf.h) and their inputs: float
// copies of yarn-frame unit vectors, wi for the T network, (wi, wo) for M.
using TransmissionMlp = FixedMlp<32, 2048>;
using ScatteringMlp = FixedMlp<64, 8192>;

inline double evalTransmission(const TransmissionMlp& net, const Vec3& wi) {
    const float x[3] = {static_cast<float>(wi.x), static_cast<float>(wi.y),
                        static_cast<float>(wi.z)};
    float y;
    net.forward(x, &y);
    return y;
}

inline Rgb evalScattering(const ScatteringMlp& net, const Vec3& wi, const Vec3& wo) {
    const float x[6] = {static_cast<float>(wi.x), static_cast<float>(wi.y),
                        static_cast<float>(wi.z), static_cast<float>(wo.x),
                        static_cast<float>(wo.y), static_cast<float>(wo.z)};
    float y[3];
    net.forward(x, y);
    return {y[0], y[1], y[2]};
}

}  // namespace weft
