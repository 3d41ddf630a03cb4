// weft/yarn/fixed_mlp.cpp — FixedMlp's forward pass in float32 SIMD, one
// kernel per instruction set (Google Highway, dynamic dispatch).
//
// Highway compiles this file once per target (hwy/foreach_target.h re-includes
// it with HWY_TARGET set to SSSE3, SSE4, AVX2, AVX3 = AVX-512 and the portable
// EMU128); HWY_EXPORT builds the table and HWY_DYNAMIC_DISPATCH picks the
// entry of the best target the CPU has. The dispatch happens once, when a
// FixedMlp is constructed (fixedMlpKernel()): the FixedMlp keeps the kernel's
// function pointer and pads its weights to that kernel's vector width, so a
// forward pass is one indirect call.
//
// The kernel (one input vector, latency-bound): a layer's outputs are
// `vectors` SIMD vectors of accumulators, processed in blocks of up to 3 or
// 4 vectors; each input j is broadcast from memory and multiply-added with
// the stored column W[:, j]. One accumulator set per input would make a chain
// of `in` dependent FMAs (4 cycles each) per vector; four sets take the
// inputs j with j mod 4 = s, so the 21-input layers' chains are 6 FMAs long,
// and the sets are
// summed pairwise at the end. The vectors are arrays of Highway vectors, which SVE and
// RVV (sizeless types) do not allow: those targets are disabled below, and
// Arm builds run NEON.
#include "weft/yarn/fixed_mlp.h"

#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SVE | HWY_SVE2 | HWY_SVE_256 | HWY_SVE2_128 | HWY_RVV)
#endif

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "weft/yarn/fixed_mlp.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace weft {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;

using Tag = hn::CappedTag<float, FixedMlpKernel::kMaxLanes>;
using Vector = hn::Vec<Tag>;

// Four accumulator sets, in every kernel: each output lane then goes through
// the same operations in the same order whatever the vector width, so the
// AVX2 and AVX-512 kernels (all kernels with FMA) give the same bits and a
// render does not depend on which of them the CPU runs. A block of one or
// two vectors has 4 or 8 independent chains (two FMA ports, latency 4); a
// block holds at most as many vectors as 4 sets of them fit in half the
// vector registers (AVX-512 has 32, the others 16). (8 sets for one or two
// AVX-512 vectors were slower: the extra column pointers spill.)
constexpr int kSets = 4;
constexpr int kBlockVectors = (HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL) ? 4 : 3;

// acc[v] += w[column, v lanes) x for one input x (column = its weights).
template <int kVectors>
HWY_INLINE void multiplyAdd(const float* HWY_RESTRICT column, float x, Vector* acc) {
    const Tag d;
    const int lanes = static_cast<int>(hn::Lanes(d));
    const Vector broadcast = hn::Set(d, x);
    for (int v = 0; v < kVectors; ++v)
        acc[v] = hn::MulAdd(hn::Load(d, column + v * lanes), broadcast, acc[v]);
}

template <int kVectors>
HWY_INLINE void add(Vector* acc, const Vector* other) {
    for (int v = 0; v < kVectors; ++v) acc[v] = hn::Add(acc[v], other[v]);
}

// z[0, kVectors lanes) = (prelu) (bias + sum_j w[j stride + .] a[j]) for one
// block of kVectors vectors of outputs; w, bias and slope point at the
// block's first output (slope is null without PReLU). The sets are written
// out and every loop has a compile-time trip count, so that the compiler
// unrolls them and the accumulators stay in registers.
template <int kVectors>
HWY_INLINE void denseBlock(const float* HWY_RESTRICT w, int stride, int in,
                           const float* HWY_RESTRICT bias, const float* HWY_RESTRICT slope,
                           const float* HWY_RESTRICT a, float* HWY_RESTRICT z) {
    const Tag d;
    const int lanes = static_cast<int>(hn::Lanes(d));
    Vector acc0[kVectors], acc1[kVectors], acc2[kVectors], acc3[kVectors];
    for (int v = 0; v < kVectors; ++v) {
        acc0[v] = hn::Load(d, bias + v * lanes);
        acc1[v] = hn::Zero(d);
        acc2[v] = hn::Zero(d);
        acc3[v] = hn::Zero(d);
    }
    const float* column = w;
    int j = 0;
    for (; j + kSets <= in; j += kSets, column += kSets * stride) {
        multiplyAdd<kVectors>(column, a[j], acc0);
        multiplyAdd<kVectors>(column + stride, a[j + 1], acc1);
        multiplyAdd<kVectors>(column + 2 * stride, a[j + 2], acc2);
        multiplyAdd<kVectors>(column + 3 * stride, a[j + 3], acc3);
    }
    // The last in mod kSets inputs, one per set (still independent chains).
    if (j < in) multiplyAdd<kVectors>(column, a[j], acc0);
    if (j + 1 < in) multiplyAdd<kVectors>(column + stride, a[j + 1], acc1);
    if (j + 2 < in) multiplyAdd<kVectors>(column + 2 * stride, a[j + 2], acc2);
    // The sum of the sets, pairwise.
    add<kVectors>(acc0, acc2);
    add<kVectors>(acc1, acc3);
    add<kVectors>(acc0, acc1);
    if (slope) {
        const Vector zero = hn::Zero(d);
        for (int v = 0; v < kVectors; ++v)
            acc0[v] = hn::MulAdd(hn::Load(d, slope + v * lanes), hn::Min(acc0[v], zero),
                                 hn::Max(acc0[v], zero));
    }
    for (int v = 0; v < kVectors; ++v) hn::Store(acc0[v], d, z + v * lanes);
}

void denseLayer(const FixedMlpLayer& layer, const float* HWY_RESTRICT params,
                const float* HWY_RESTRICT a, float* HWY_RESTRICT z) {
    const Tag d;
    const int lanes = static_cast<int>(hn::Lanes(d));
    const int stride = layer.outPadded;
    const float* w = params + layer.offset;
    const float* bias = w + layer.in * stride;
    const float* slope = layer.prelu ? bias + stride : nullptr;
    const int vectors = stride / lanes;
    for (int v = 0; v < vectors; v += kBlockVectors) {
        const int o = v * lanes;
        const float* s = slope ? slope + o : nullptr;
        switch (std::min(kBlockVectors, vectors - v)) {
            case 1:
                denseBlock<1>(w + o, stride, layer.in, bias + o, s, a, z + o);
                break;
            case 2:
                denseBlock<2>(w + o, stride, layer.in, bias + o, s, a, z + o);
                break;
            case 3:
                denseBlock<3>(w + o, stride, layer.in, bias + o, s, a, z + o);
                break;
            default:
                denseBlock<4>(w + o, stride, layer.in, bias + o, s, a, z + o);
                break;
        }
    }
}

using Layer = void (*)(const FixedMlpLayer&, const float*, const float*, float*);

// The layers in turn, the hidden values alternating between a and b, the
// last layer's into z.
template <Layer kLayer>
void runLayers(const FixedMlpLayer* layers, int layerCount, const float* params, const float* x,
               float* a, float* b, float* z) {
    const float* input = x;
    for (int l = 0; l < layerCount; ++l) {
        float* output = l + 1 == layerCount ? z : (l % 2 == 0 ? a : b);
        kLayer(layers[l], params, input, output);
        input = output;
    }
}

// The batched kernel: one query per lane. Activations are stored by input,
// a[j lanes + lane], so that input j of every query is one vector; each
// output o is an accumulator vector, and w[j, o] is broadcast. Every lane
// does, per output, exactly the single-query kernel's operations in its
// order (bias in set 0, input j in set j mod 4, the sets summed pairwise,
// then PReLU), so forwardBatch gives forward's bits on every target. A block
// of kBatchOutputs outputs keeps 4 x kBatchOutputs accumulators in
// registers and loads each input vector once per block.
constexpr int kBatchOutputs = (HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL) ? 6 : 3;

template <int kOutputs>
HWY_INLINE void batchBlock(const float* HWY_RESTRICT w, int stride, int in,
                           const float* HWY_RESTRICT bias, const float* HWY_RESTRICT slope,
                           const float* HWY_RESTRICT a, float* HWY_RESTRICT z) {
    const Tag d;
    const size_t lanes = hn::Lanes(d);
    Vector acc0[kOutputs], acc1[kOutputs], acc2[kOutputs], acc3[kOutputs];
    for (int g = 0; g < kOutputs; ++g) {
        acc0[g] = hn::Set(d, bias[g]);
        acc1[g] = hn::Zero(d);
        acc2[g] = hn::Zero(d);
        acc3[g] = hn::Zero(d);
    }
    auto input = [&](int j, Vector* acc) {
        const Vector x = hn::Load(d, a + j * lanes);
        const float* column = w + j * stride;
        for (int g = 0; g < kOutputs; ++g) acc[g] = hn::MulAdd(hn::Set(d, column[g]), x, acc[g]);
    };
    int j = 0;
    for (; j + kSets <= in; j += kSets) {
        input(j, acc0);
        input(j + 1, acc1);
        input(j + 2, acc2);
        input(j + 3, acc3);
    }
    if (j < in) input(j, acc0);
    if (j + 1 < in) input(j + 1, acc1);
    if (j + 2 < in) input(j + 2, acc2);
    add<kOutputs>(acc0, acc2);
    add<kOutputs>(acc1, acc3);
    add<kOutputs>(acc0, acc1);
    const Vector zero = hn::Zero(d);
    for (int g = 0; g < kOutputs; ++g) {
        if (slope)
            acc0[g] =
                hn::MulAdd(hn::Set(d, slope[g]), hn::Min(acc0[g], zero), hn::Max(acc0[g], zero));
        hn::Store(acc0[g], d, z + g * lanes);
    }
}

// z[o lanes + lane] for the layer's `out` outputs (not its padding).
void batchLayer(const FixedMlpLayer& layer, const float* HWY_RESTRICT params,
                const float* HWY_RESTRICT a, float* HWY_RESTRICT z) {
    const size_t lanes = hn::Lanes(Tag());
    const int stride = layer.outPadded;
    const float* w = params + layer.offset;
    const float* bias = w + layer.in * stride;
    const float* slope = layer.prelu ? bias + stride : nullptr;
    for (int o = 0; o < layer.out; o += kBatchOutputs) {
        const float* s = slope ? slope + o : nullptr;
        float* zo = z + o * lanes;
        // The last block holds the rest (a block of 1 would load the input
        // vector for every multiply-add).
        switch (std::min(kBatchOutputs, layer.out - o)) {
            case 1:
                batchBlock<1>(w + o, stride, layer.in, bias + o, s, a, zo);
                break;
            case 2:
                batchBlock<2>(w + o, stride, layer.in, bias + o, s, a, zo);
                break;
#if HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL
            case 3:
                batchBlock<3>(w + o, stride, layer.in, bias + o, s, a, zo);
                break;
            case 4:
                batchBlock<4>(w + o, stride, layer.in, bias + o, s, a, zo);
                break;
            case 5:
                batchBlock<5>(w + o, stride, layer.in, bias + o, s, a, zo);
                break;
#endif
            default:
                batchBlock<kBatchOutputs>(w + o, stride, layer.in, bias + o, s, a, zo);
                break;
        }
    }
}

// The output function in place on z[0, count), count a multiple of the
// vector width; elementwise, so a value's result does not depend on its
// neighbours (forward and forwardBatch agree). Highway's Exp (1 ulp) in place
// of std::exp: 3 calls of libm per M query cost as much as a batched layer.
void applyOutput(OutputFunction function, float* HWY_RESTRICT z, int count) {
    if (function == OutputFunction::Identity) return;
    const Tag d;
    const int lanes = static_cast<int>(hn::Lanes(d));
    const Vector one = hn::Set(d, 1.0f), cap = hn::Set(d, 80.0f), zero = hn::Zero(d);
    for (int k = 0; k < count; k += lanes) {
        const Vector v = hn::Load(d, z + k);
        Vector y;
        if (function == OutputFunction::Exp) {
            y = hn::Exp(d, hn::Min(v, cap));  // cannot overflow
        } else {
            // Sigmoid from e = exp(-|z|) <= 1 (Exp is 0 below -104, as a
            // float's exp is): 1 / (1 + e) for z >= 0, e / (1 + e) below.
            const Vector e = hn::Exp(d, hn::Neg(hn::Abs(v)));
            const Vector r = hn::Div(one, hn::Add(one, e));
            y = hn::IfThenElse(hn::Ge(v, zero), r, hn::Mul(e, r));
        }
        hn::Store(y, d, z + k);
    }
}

}  // namespace

FixedMlpKernel selectKernel() {
    FixedMlpKernel kernel;
    kernel.forward = &runLayers<denseLayer>;
    kernel.forwardBatch = &runLayers<batchLayer>;
    kernel.applyOutput = &applyOutput;
    kernel.lanes = static_cast<int>(hn::Lanes(Tag()));
    kernel.fusedMultiplyAdd = HWY_NATIVE_FMA != 0;
    kernel.target = hwy::TargetName(HWY_TARGET);
    return kernel;
}

}  // namespace HWY_NAMESPACE
}  // namespace weft
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "weft/yarn/highway_targets.h"

namespace weft {

HWY_EXPORT(selectKernel);

FixedMlpKernel fixedMlpKernel() { return HWY_DYNAMIC_DISPATCH(selectKernel)(); }

std::vector<FixedMlpKernel> fixedMlpKernels() {
    return everyHighwayTarget([] { return HWY_DYNAMIC_DISPATCH(selectKernel)(); });
}

}  // namespace weft
#endif  // HWY_ONCE
