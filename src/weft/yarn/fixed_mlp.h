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
//     option, docs/design.md 6); all parameters after padding fit in Capacity floats;
//   - forward() is float32 SIMD through Google Highway (libhwy-dev) with
//     dynamic dispatch (fixed_mlp.cpp): the kernel is compiled for every x86
//     instruction set from SSSE3 to AVX-512 (plus Highway's portable EMU128),
//     and the constructor binds the best one that this CPU runs, so a
//     portable build (no -march flag) gets AVX2 + FMA or AVX-512 where the
//     machine has them. Highway rather than Eigen's fixed-size matrices or
//     xsimd: both of those pick the instruction set at compile time (-march),
//     so a binary built for any x86-64 would run SSE2 everywhere; Highway's
//     runtime dispatch needs no flag and costs one indirect call per forward;
//   - each layer is stored column-major with its output count padded with
//     zero weights to a multiple of the kernel's vector width (lanes(): 4
//     floats for SSE, 8 for AVX2, 16 for AVX-512); y += W[:, j] x[j] is a
//     multiply-add of a broadcast input into accumulator vectors held in
//     registers; four accumulator sets take alternate inputs (j mod 4) so
//     that one call is not a single chain of dependent multiply-adds; every
//     kernel does the same operations per output in the same order, so the
//     kernels with FMA (AVX2, AVX-512) give the same bits; padded outputs
//     stay 0;
//   - PReLU as max(z, 0) + slope min(z, 0): the same value, no branches;
//   - float arithmetic like the training code; forwardScalar() is the plain
//     C++ reference on the same stored weights, with each layer's sums in
//     double (below); fixed_mlp_test holds forward() to it within 1e-5
//     relative for every instruction set the CPU runs;
//   - the exp output saturates at e^80 so that no input can give +inf; the
//     kernels take exp from Highway (1 ulp; hwy/contrib/math), the scalar
//     reference from libm;
//   - forwardBatch() runs one query per vector lane (a vector per input,
//     hidden value and output, each weight broadcast), the throughput form
//     for callers with many queries at once: each lane does forward()'s
//     operations in its order, so the bits are forward()'s.
// For the 6-21-21-21-3 network the weights take 6-9 KB: they stay in L1.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/yarn/network.h"
#include "weft/yarn/network_capacity.h"

namespace weft {

// One layer of a FixedMlp's stored parameters (offsets in floats): `in`
// columns of `outPadded` weights, then `outPadded` biases, then (with PReLU)
// `outPadded` slopes.
struct FixedMlpLayer {
    int in = 0, out = 0, outPadded = 0, offset = 0;
    bool prelu = false;
};

// The compiled forward pass of one instruction set (fixed_mlp.cpp).
struct FixedMlpKernel {
    // No kernel is wider than this (floats per vector); capacities are
    // checked as if every layer were padded to it, so that whether a network
    // fits does not depend on the machine (network_capacity.h).
    static constexpr int kMaxLanes = kNetworkPaddingLanes;
    // z[0, outPadded of the last layer) = the last layer's pre-activation of
    // the network at x; `a` and `b` hold the hidden activations (each a
    // padded width long). z, a and b are aligned to 64 bytes.
    using Forward = void (*)(const FixedMlpLayer* layers, int layerCount, const float* params,
                             const float* x, float* a, float* b, float* z);
    Forward forward = nullptr;
    // The same network for `lanes` queries at once, one per lane: x, a, b
    // and z hold a vector per input, hidden value or output (x[j lanes +
    // lane]); each lane gets the bits forward() gives its query.
    Forward forwardBatch = nullptr;
    // The output function (sigmoid, exp saturated at e^80, identity) in
    // place on z[0, count), count a multiple of `lanes`.
    using ApplyOutput = void (*)(OutputFunction function, float* z, int count);
    ApplyOutput applyOutput = nullptr;
    int lanes = 1;                   // floats per vector: the padding unit
    bool fusedMultiplyAdd = false;  // one rounding per multiply-add (AVX2, AVX-512, NEON)
    const char* target = "none";    // Highway's name: "AVX3", "AVX2", "SSE4", "SCALAR", ...
};

// The kernel of the best instruction set that this CPU runs (Highway's
// dynamic dispatch).
FixedMlpKernel fixedMlpKernel();
// Every compiled kernel that this CPU runs, best first (for tests and
// benchmarks; switches Highway's target choice while it runs, so do not call
// it while another thread constructs a FixedMlp).
std::vector<FixedMlpKernel> fixedMlpKernels();

template <int MaxWidth, int Capacity>
class FixedMlp {
  public:
    static constexpr int kMaxLayers = kMaxNetworkLayers;

    FixedMlp() = default;

    // Copies `net`; InputError starting with `name` ("m_net") when it is wider,
    // deeper or larger than this evaluator supports.
    FixedMlp(const NetworkWeights& net, const std::string& name)
        : FixedMlp(net, name, fixedMlpKernel()) {}
    // The same with a given kernel (one of fixedMlpKernels()).
    FixedMlp(const NetworkWeights& net, const std::string& name, const FixedMlpKernel& kernel)
        : kernel_(kernel), output_(net.output) {
        const auto& layers = net.layers;
        if (layers.empty() || layers.size() > static_cast<size_t>(kMaxLayers))
            throw InputError(name + ": " + std::to_string(layers.size()) +
                             " layers; the renderer's network evaluator supports 1 to " +
                             std::to_string(kMaxLayers));
        const int lanes = kernel_.lanes;
        int offset = 0;
        long long worstCase = 0;
        layerCount_ = static_cast<int>(layers.size());
        for (int l = 0; l < layerCount_; ++l) {
            const NetworkLayer& src = layers[l];
            if (src.in > MaxWidth || src.out > MaxWidth)
                throw InputError(name + ": layers[" + std::to_string(l) + "] is " +
                                 std::to_string(src.out) + " x " + std::to_string(src.in) +
                                 "; the renderer's network evaluator supports widths up to " +
                                 std::to_string(MaxWidth));
            FixedMlpLayer& dst = layers_[l];
            dst.in = src.in;
            dst.out = src.out;
            dst.outPadded = roundUp(src.out, lanes);
            dst.prelu = src.hasPrelu();
            dst.offset = offset;
            offset += static_cast<int>(paddedLayerFloats(dst.in, dst.out, dst.prelu, lanes));
            worstCase += paddedLayerFloats(dst.in, dst.out, dst.prelu);
            if (worstCase > Capacity)
                throw InputError(name + ": " + std::to_string(net.parameterCount()) +
                                 " parameters need more than the " + std::to_string(Capacity) +
                                 " (after padding to blocks of " +
                                 std::to_string(FixedMlpKernel::kMaxLanes) +
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
    // The instruction set forward() runs ("AVX3", "AVX2", ...; fixedMlpKernel()).
    const char* target() const { return kernel_.target; }

    // y[0, outputs()) = net(x[0, inputs())): the SIMD kernel.
    void forward(const float* x, float* y) const {
        if (layerCount_ == 0) return;  // a default-constructed evaluator has no kernel
        alignas(64) float a[kPadded], b[kPadded], z[kPadded];
        kernel_.forward(layers_.data(), layerCount_, params_.data(), x, a, b, z);
        const int out = outputs();
        kernel_.applyOutput(output_, z, roundUp(out, kernel_.lanes));
        std::copy(z, z + out, y);
    }

    // y[k outputs() + o] = output o of the network at x[k inputs(), (k + 1)
    // inputs()) for the `count` queries k: the batched kernel runs lanes()
    // queries per call, each lane through forward()'s operations in its
    // order, so every output has forward()'s bits (for any count, and
    // whichever lane a query falls in); a partial last call computes on
    // zero-filled lanes and writes only the count queries' outputs. About
    // 3.5 times the single query's throughput for the M network (bench/bsdf).
    void forwardBatch(const float* x, int count, float* y) const {
        if (layerCount_ == 0) return;
        const int lanes = kernel_.lanes, in = inputs(), out = outputs();
        alignas(64) float xs[kBatchFloats], a[kBatchFloats], b[kBatchFloats], z[kBatchFloats];
        for (int first = 0; first < count; first += lanes) {
            const int n = std::min(lanes, count - first);
            for (int j = 0; j < in; ++j) {
                for (int k = 0; k < n; ++k) xs[j * lanes + k] = x[(first + k) * in + j];
                for (int k = n; k < lanes; ++k) xs[j * lanes + k] = 0.0f;
            }
            kernel_.forwardBatch(layers_.data(), layerCount_, params_.data(), xs, a, b, z);
            kernel_.applyOutput(output_, z, out * lanes);
            for (int k = 0; k < n; ++k)
                for (int o = 0; o < out; ++o) y[(first + k) * out + o] = z[o * lanes + k];
        }
    }
    int lanes() const { return kernel_.lanes; }

    // The same function in plain C++, the reference for forward(): each
    // output's sum (bias, then the inputs in order) in double, rounded to
    // float once per layer as the kernels store it. The kernels sum in float;
    // on the shipped networks, whose hidden values reach 1e2 - 1e3 and cancel
    // to pre-activations of order 1, float rounding alone moves an output by
    // up to about 1e-5 relative, so a float reference would be as far from
    // the exact value as the kernels are.
    void forwardScalar(const float* x, float* y) const {
        float bufferA[kPadded], bufferB[kPadded];
        const float* a = x;
        float* z = bufferA;
        for (int l = 0; l < layerCount_; ++l) {
            const FixedMlpLayer& layer = layers_[l];
            const float* w = params_.data() + layer.offset;
            const float* bias = w + layer.in * layer.outPadded;
            for (int o = 0; o < layer.out; ++o) {
                double sum = bias[o];
                for (int j = 0; j < layer.in; ++j)
                    sum += static_cast<double>(w[j * layer.outPadded + o]) * a[j];
                if (layer.prelu && sum < 0) sum *= bias[layer.outPadded + o];
                z[o] = static_cast<float>(sum);
            }
            a = z;
            z = z == bufferA ? bufferB : bufferA;
        }
        scalarOutput(a, y);
    }

  private:
    // The scratch length: a width up to MaxWidth padded for the widest kernel.
    static constexpr int kPadded =
        (MaxWidth + FixedMlpKernel::kMaxLanes - 1) / FixedMlpKernel::kMaxLanes *
        FixedMlpKernel::kMaxLanes;

    static int roundUp(int n, int lanes) { return (n + lanes - 1) / lanes * lanes; }

    // The batched kernel's scratch: a vector per value of a layer's widest side.
    static constexpr int kBatchFloats = MaxWidth * FixedMlpKernel::kMaxLanes;

    // The output function in libm, for forwardScalar.
    float outputValue(float z) const {
        switch (output_) {
            case OutputFunction::Sigmoid:
                return 1.0f / (1.0f + std::exp(-z));
            case OutputFunction::Exp:
                return std::exp(std::min(z, 80.0f));
            case OutputFunction::Identity:
                break;
        }
        return z;
    }

    void scalarOutput(const float* z, float* y) const {
        const int out = outputs();
        for (int o = 0; o < out; ++o) y[o] = outputValue(z[o]);
    }

    std::array<FixedMlpLayer, kMaxLayers> layers_{};
    int layerCount_ = 0;
    FixedMlpKernel kernel_{};
    OutputFunction output_ = OutputFunction::Identity;
    alignas(64) std::array<float, Capacity> params_{};
};

// The yarn model's two evaluators (yarn_bsdf.h), of the sizes that
// network_capacity.h gives (weft fit checks its networks against the same
// numbers), and their inputs: float copies of yarn-frame unit vectors, wi for
// the T network, (wi, wo) for M.
using TransmissionMlp = FixedMlp<kTransmissionCapacity.maxWidth, kTransmissionCapacity.floats>;
using ScatteringMlp = FixedMlp<kScatteringCapacity.maxWidth, kScatteringCapacity.floats>;
static_assert(TransmissionMlp::kMaxLayers == kTransmissionCapacity.maxLayers &&
              ScatteringMlp::kMaxLayers == kScatteringCapacity.maxLayers);

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

// out[k] = evalScattering(net, wi[k wiStep], wo[k]) for k < count, bit for
// bit (FixedMlp::forwardBatch); wiStep 0: one wi for every wo.
inline void evalScatteringBatch(const ScatteringMlp& net, const Vec3* wi, size_t wiStep,
                                const Vec3* wo, size_t count, Rgb* out) {
    constexpr size_t kChunk = 64;
    float x[6 * kChunk], y[3 * kChunk];
    for (size_t first = 0; first < count; first += kChunk) {
        const size_t n = std::min(kChunk, count - first);
        for (size_t k = 0; k < n; ++k) {
            const Vec3 &i = wi[(first + k) * wiStep], &o = wo[first + k];
            const float q[6] = {static_cast<float>(i.x), static_cast<float>(i.y),
                                static_cast<float>(i.z), static_cast<float>(o.x),
                                static_cast<float>(o.y), static_cast<float>(o.z)};
            std::copy(q, q + 6, x + 6 * k);
        }
        net.forwardBatch(x, static_cast<int>(n), y);
        for (size_t k = 0; k < n; ++k) out[first + k] = {y[3 * k], y[3 * k + 1], y[3 * k + 2]};
    }
}

// out[k] = evalTransmission(net, wi[k]) for k < count, bit for bit.
inline void evalTransmissionBatch(const TransmissionMlp& net, const Vec3* wi, size_t count,
                                  double* out) {
    constexpr size_t kChunk = 64;
    float x[3 * kChunk], y[kChunk];
    for (size_t first = 0; first < count; first += kChunk) {
        const size_t n = std::min(kChunk, count - first);
        for (size_t k = 0; k < n; ++k) {
            const Vec3& i = wi[first + k];
            x[3 * k] = static_cast<float>(i.x);
            x[3 * k + 1] = static_cast<float>(i.y);
            x[3 * k + 2] = static_cast<float>(i.z);
        }
        net.forwardBatch(x, static_cast<int>(n), y);
        for (size_t k = 0; k < n; ++k) out[first + k] = y[k];
    }
}

}  // namespace weft
