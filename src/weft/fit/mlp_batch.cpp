// weft/fit/mlp_batch.cpp — MlpBatch's loops over samples in float32 SIMD, one
// kernel per instruction set (Google Highway, dynamic dispatch, as
// yarn/fixed_mlp.cpp), and the passes that call them.
//
// Every vector lane is one sample. A dense layer keeps 8 vectors of
// accumulators (4 rows x 2 vectors, or 8 rows x 1 AVX-512 vector): 8
// independent chains of FMAs for two FMA ports of latency 4, with one load
// of the inputs shared by the rows and a broadcast weight per row. A sum over
// samples (a gradient) runs kMlpSampleGroup = 16 partial sums, as 16 / lanes
// vectors, over blocks of weights so that 8 vectors accumulate at once.
#include "weft/fit/mlp_batch.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SVE | HWY_SVE2 | HWY_SVE_256 | HWY_SVE2_128 | HWY_RVV)
#endif

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "weft/fit/mlp_batch.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include <hwy/contrib/math/math-inl.h>  // Exp, Log1p: after highway.h

HWY_BEFORE_NAMESPACE();
namespace weft {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;

using Tag = hn::CappedTag<float, kMlpSampleGroup>;
using Vector = hn::Vec<Tag>;
constexpr int kLanes = static_cast<int>(hn::MaxLanes(Tag()));
constexpr int kGroupVectors = kMlpSampleGroup / kLanes;  // vectors per 16 samples
// Accumulator vectors held at once (above).
constexpr int kAccumulators = 8;

// The 16 partial sums of a group, added in one fixed tree.
float sumOfGroup(const Vector* partial) {
    const Tag d;
    HWY_ALIGN float s[kMlpSampleGroup];
    for (int g = 0; g < kGroupVectors; ++g) hn::Store(partial[g], d, s + g * kLanes);
    for (int i = 0; i < 8; ++i) s[i] += s[i + 8];
    for (int i = 0; i < 4; ++i) s[i] += s[i + 4];
    return (s[0] + s[2]) + (s[1] + s[3]);
}

// z[r] for kRows rows and kVectors vectors of samples from k on.
template <int kRows, int kVectors>
HWY_INLINE void denseBlock(const float* HWY_RESTRICT w, int rowStep, int colStep,
                           const float* HWY_RESTRICT bias, int cols, const float* HWY_RESTRICT a,
                           float* HWY_RESTRICT z, int stride, int k) {
    const Tag d;
    Vector acc[kRows][kVectors];
    for (int r = 0; r < kRows; ++r) {
        const Vector b = bias ? hn::Set(d, bias[r]) : hn::Zero(d);
        for (int v = 0; v < kVectors; ++v) acc[r][v] = b;
    }
    for (int j = 0; j < cols; ++j) {
        const float* aj = a + static_cast<size_t>(j) * stride + k;
        Vector x[kVectors];
        for (int v = 0; v < kVectors; ++v) x[v] = hn::Load(d, aj + v * kLanes);
        for (int r = 0; r < kRows; ++r) {
            const Vector weight = hn::Set(d, w[r * rowStep + j * colStep]);
            for (int v = 0; v < kVectors; ++v) acc[r][v] = hn::MulAdd(weight, x[v], acc[r][v]);
        }
    }
    for (int r = 0; r < kRows; ++r)
        for (int v = 0; v < kVectors; ++v)
            hn::Store(acc[r][v], d, z + static_cast<size_t>(r) * stride + k + v * kLanes);
}

void dense(const float* w, int rowStep, int colStep, const float* bias, int rows, int cols,
           const float* a, float* z, int stride, int n) {
    constexpr int kVectors = kLanes >= kMlpSampleGroup ? 1 : 2;
    constexpr int kRows = kAccumulators / kVectors;
    for (int k = 0; k < n; k += kVectors * kLanes) {
        int r = 0;
        for (; r + kRows <= rows; r += kRows)
            denseBlock<kRows, kVectors>(w + r * rowStep, rowStep, colStep,
                                        bias ? bias + r : nullptr, cols, a,
                                        z + static_cast<size_t>(r) * stride, stride, k);
        for (; r < rows; ++r)
            denseBlock<1, kVectors>(w + r * rowStep, rowStep, colStep, bias ? bias + r : nullptr,
                                    cols, a, z + static_cast<size_t>(r) * stride, stride, k);
    }
}

void prelu(const float* slope, int rows, const float* z, float* a, int stride, int n) {
    const Tag d;
    const Vector zero = hn::Zero(d);
    for (int r = 0; r < rows; ++r) {
        const Vector s = hn::Set(d, slope[r]);
        const float* zr = z + static_cast<size_t>(r) * stride;
        float* ar = a + static_cast<size_t>(r) * stride;
        for (int k = 0; k < n; k += kLanes) {
            const Vector v = hn::Load(d, zr + k);
            hn::Store(hn::MulAdd(s, hn::Min(v, zero), hn::Max(v, zero)), d, ar + k);
        }
    }
}

void preluBackward(const float* slope, int rows, const float* z, float* da, float* dSlope,
                   int stride, int n) {
    const Tag d;
    const Vector zero = hn::Zero(d);
    for (int r = 0; r < rows; ++r) {
        const Vector s = hn::Set(d, slope[r]);
        const float* zr = z + static_cast<size_t>(r) * stride;
        float* dar = da + static_cast<size_t>(r) * stride;
        Vector partial[kGroupVectors];
        for (int g = 0; g < kGroupVectors; ++g) partial[g] = zero;
        for (int k = 0; k < n; k += kMlpSampleGroup)
            for (int g = 0; g < kGroupVectors; ++g) {
                const int at = k + g * kLanes;
                const Vector zv = hn::Load(d, zr + at), dv = hn::Load(d, dar + at);
                partial[g] = hn::MulAdd(dv, hn::Min(zv, zero), partial[g]);
                hn::Store(hn::IfThenElse(hn::Lt(zv, zero), hn::Mul(dv, s), dv), d, dar + at);
            }
        dSlope[r] = sumOfGroup(partial);
    }
}

// dW[r][j0 + jj] for kCols columns of one row r.
template <int kCols>
HWY_INLINE void weightGradientBlock(const float* HWY_RESTRICT dzr, const float* HWY_RESTRICT a,
                                    int j0, float* HWY_RESTRICT dWr, int stride, int n) {
    const Tag d;
    Vector partial[kCols][kGroupVectors];
    for (int c = 0; c < kCols; ++c)
        for (int g = 0; g < kGroupVectors; ++g) partial[c][g] = hn::Zero(d);
    for (int k = 0; k < n; k += kMlpSampleGroup)
        for (int g = 0; g < kGroupVectors; ++g) {
            const int at = k + g * kLanes;
            const Vector dv = hn::Load(d, dzr + at);
            for (int c = 0; c < kCols; ++c)
                partial[c][g] = hn::MulAdd(
                    dv, hn::Load(d, a + static_cast<size_t>(j0 + c) * stride + at), partial[c][g]);
        }
    for (int c = 0; c < kCols; ++c) dWr[j0 + c] = sumOfGroup(partial[c]);
}

void weightGradient(const float* dz, int rows, const float* a, int cols, float* dW, float* db,
                    int stride, int n) {
    constexpr int kCols = kGroupVectors >= kAccumulators ? 1 : kAccumulators / kGroupVectors;
    const Tag d;
    for (int r = 0; r < rows; ++r) {
        const float* dzr = dz + static_cast<size_t>(r) * stride;
        float* dWr = dW + static_cast<size_t>(r) * cols;
        int j = 0;
        for (; j + kCols <= cols; j += kCols) weightGradientBlock<kCols>(dzr, a, j, dWr, stride, n);
        for (; j < cols; ++j) weightGradientBlock<1>(dzr, a, j, dWr, stride, n);
        Vector partial[kGroupVectors];
        for (int g = 0; g < kGroupVectors; ++g) partial[g] = hn::Zero(d);
        for (int k = 0; k < n; k += kMlpSampleGroup)
            for (int g = 0; g < kGroupVectors; ++g)
                partial[g] = hn::Add(partial[g], hn::Load(d, dzr + k + g * kLanes));
        db[r] = sumOfGroup(partial);
    }
}

void output(OutputFunction f, float* y, int rows, int stride, int n) {
    if (f == OutputFunction::Identity) return;
    const Tag d;
    const Vector one = hn::Set(d, 1.0f), limit = hn::Set(d, 80.0f);
    for (int r = 0; r < rows; ++r) {
        float* yr = y + static_cast<size_t>(r) * stride;
        for (int k = 0; k < n; k += kLanes) {
            const Vector z = hn::Load(d, yr + k);
            const Vector out =
                f == OutputFunction::Exp
                    ? hn::Exp(d, hn::Min(z, limit))
                    : hn::Div(one, hn::Add(one, hn::Exp(d, hn::Min(hn::Neg(z), limit))));
            hn::Store(out, d, yr + k);
        }
    }
}

void outputBackward(OutputFunction f, const float* y, float* dy, int rows, int stride, int n) {
    if (f == OutputFunction::Identity) return;
    const Tag d;
    const Vector one = hn::Set(d, 1.0f);
    for (int r = 0; r < rows; ++r) {
        const float* yr = y + static_cast<size_t>(r) * stride;
        float* dr = dy + static_cast<size_t>(r) * stride;
        for (int k = 0; k < n; k += kLanes) {
            const Vector yv = hn::Load(d, yr + k);
            const Vector slope =
                f == OutputFunction::Exp ? yv : hn::Mul(yv, hn::Sub(one, yv));  // exp', sigmoid'
            hn::Store(hn::Mul(hn::Load(d, dr + k), slope), d, dr + k);
        }
    }
}

void residual(Loss loss, const float* y, const float* target, int targetStride, float* diff,
              float* dy, float scale, int rows, int stride, int n) {
    const Tag d;
    const Vector one = hn::Set(d, 1.0f), s = hn::Set(d, scale);
    for (int r = 0; r < rows; ++r) {
        const size_t row = static_cast<size_t>(r) * stride;
        for (int k = 0; k < n; k += kLanes) {
            const Vector yv = hn::Load(d, y + row + k);
            const Vector tv = hn::Load(d, target + static_cast<size_t>(r) * targetStride + k);
            Vector dv, dDiff;
            if (loss == Loss::LogMse) {
                dv = hn::Sub(hn::Log1p(d, yv), hn::Log1p(d, tv));
                dDiff = hn::Div(one, hn::Add(one, yv));
            } else {
                dv = hn::Sub(yv, tv);
                dDiff = one;
            }
            hn::Store(dv, d, diff + row + k);
            hn::Store(hn::Mul(hn::Mul(s, dv), dDiff), d, dy + row + k);
        }
    }
}

}  // namespace

MlpBatchKernel selectMlpBatchKernel() {
    MlpBatchKernel kernel;
    kernel.dense = &dense;
    kernel.prelu = &prelu;
    kernel.preluBackward = &preluBackward;
    kernel.weightGradient = &weightGradient;
    kernel.output = &output;
    kernel.outputBackward = &outputBackward;
    kernel.residual = &residual;
    kernel.target = hwy::TargetName(HWY_TARGET);
    kernel.fusedMultiplyAdd = HWY_NATIVE_FMA != 0;
    return kernel;
}

}  // namespace HWY_NAMESPACE
}  // namespace weft
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "weft/yarn/highway_targets.h"

namespace weft {

HWY_EXPORT(selectMlpBatchKernel);

MlpBatchKernel mlpBatchKernel() { return HWY_DYNAMIC_DISPATCH(selectMlpBatchKernel)(); }

std::vector<MlpBatchKernel> mlpBatchKernels() {
    return everyHighwayTarget([] { return HWY_DYNAMIC_DISPATCH(selectMlpBatchKernel)(); });
}

namespace {

int roundUpToGroup(int n) { return (n + kMlpSampleGroup - 1) / kMlpSampleGroup * kMlpSampleGroup; }

}  // namespace

BatchRows::BatchRows(int rows, int capacity)
    : rows_(rows), capacity_(capacity), stride_(roundUpToGroup(capacity)) {
    if (rows < 1 || capacity < 1) throw std::invalid_argument("BatchRows: empty shape");
    const size_t size = static_cast<size_t>(rows) * stride_;
    data_ = hwy::AllocateAligned<float>(size);
    if (!data_) throw std::bad_alloc();
    std::fill(data_.get(), data_.get() + size, 0.0f);
}

void setInputColumn(BatchRows& x, int k, const Vec3& w) {
    x(0, k) = static_cast<float>(w.x);
    x(1, k) = static_cast<float>(w.y);
    x(2, k) = static_cast<float>(w.z);
}

void setInputColumn(BatchRows& x, int k, const Vec3& wi, const Vec3& wo) {
    setInputColumn(x, k, wi);
    x(3, k) = static_cast<float>(wo.x);
    x(4, k) = static_cast<float>(wo.y);
    x(5, k) = static_cast<float>(wo.z);
}

MlpBatch::MlpBatch(const Mlp<float>& net, int capacity, const MlpBatchKernel& kernel)
    : net_(&net), kernel_(kernel), capacity_(capacity) {
    const auto& layers = net.layers();
    int widest = 1;
    acts_.emplace_back(net.inputs(), capacity);
    for (size_t l = 0; l < layers.size(); ++l) {
        acts_.emplace_back(layers[l].out, capacity);
        pre_.emplace_back(layers[l].prelu ? layers[l].out : 1, capacity);
        widest = std::max(widest, layers[l].in);
    }
    dOut_ = BatchRows(net.outputs(), capacity);
    diff_ = BatchRows(net.outputs(), capacity);
    dA_ = BatchRows(widest, capacity);
    dB_ = BatchRows(widest, capacity);
}

int MlpBatch::padded() const { return roundUpToGroup(n_); }

void MlpBatch::forward(const BatchRows& x, int n) {
    if (n < 1 || n > capacity_ || x.rows() < net_->inputs() || x.capacity() < n)
        throw std::invalid_argument("MlpBatch::forward: the chunk does not fit");
    n_ = n;
    const int count = padded();
    BatchRows& in = acts_.front();
    for (int r = 0; r < in.rows(); ++r) {
        std::memcpy(in.row(r), x.row(r), sizeof(float) * static_cast<size_t>(n));
        std::fill(in.row(r) + n, in.row(r) + count, 0.0f);
    }
    const auto& layers = net_->layers();
    const float* params = net_->parameters().data();
    const int stride = in.stride();
    for (size_t l = 0; l < layers.size(); ++l) {
        const auto& layer = layers[l];
        BatchRows& out = layer.prelu ? pre_[l] : acts_[l + 1];
        kernel_.dense(params + layer.weightOffset, layer.in, 1, params + layer.biasOffset,
                      layer.out, layer.in, acts_[l].row(0), out.row(0), stride, count);
        if (layer.prelu)
            kernel_.prelu(params + layer.preluOffset, layer.out, out.row(0), acts_[l + 1].row(0),
                          stride, count);
    }
    kernel_.output(net_->output(), acts_.back().row(0), net_->outputs(), stride, count);
}

void MlpBatch::backward(std::vector<float>& gradient) {
    const auto& layers = net_->layers();
    const float* params = net_->parameters().data();
    const int count = padded(), stride = dOut_.stride();
    // Every parameter is a weight, a bias or a slope: each is written below.
    gradient.resize(net_->parameters().size());
    for (int r = 0; r < dOut_.rows(); ++r) std::fill(dOut_.row(r) + n_, dOut_.row(r) + count, 0.0f);
    kernel_.outputBackward(net_->output(), acts_.back().row(0), dOut_.row(0), dOut_.rows(), stride,
                           count);
    BatchRows* dz = &dOut_;
    for (size_t li = layers.size(); li-- > 0;) {
        const auto& layer = layers[li];
        kernel_.weightGradient(dz->row(0), layer.out, acts_[li].row(0), layer.in,
                               gradient.data() + layer.weightOffset,
                               gradient.data() + layer.biasOffset, stride, count);
        if (li == 0) break;
        // dL/d(activation of the previous layer): W^T dz, then through its PReLU.
        BatchRows* da = dz == &dA_ ? &dB_ : &dA_;
        kernel_.dense(params + layer.weightOffset, 1, layer.in, nullptr, layer.in, layer.out,
                      dz->row(0), da->row(0), stride, count);
        const auto& prev = layers[li - 1];
        if (prev.prelu)
            kernel_.preluBackward(params + prev.preluOffset, prev.out, pre_[li - 1].row(0),
                                  da->row(0), gradient.data() + prev.preluOffset, stride, count);
        dz = da;
    }
}

float MlpBatch::lossAndGradient(const BatchRows& x, const BatchRows& target, int n, Loss loss,
                                std::vector<float>& gradient) {
    forward(x, n);
    if (target.rows() < net_->outputs() || target.capacity() < n)
        throw std::invalid_argument("MlpBatch::lossAndGradient: the targets do not fit");
    // Both strides are multiples of kMlpSampleGroup, so the padded samples are in every row.
    kernel_.residual(loss, acts_.back().row(0), target.row(0), target.stride(), diff_.row(0),
                     dOut_.row(0), 2.0f / static_cast<float>(n), net_->outputs(), dOut_.stride(),
                     padded());
    double total = 0;
    for (int r = 0; r < diff_.rows(); ++r)
        for (int k = 0; k < n; ++k) total += static_cast<double>(diff_(r, k)) * diff_(r, k);
    backward(gradient);
    return static_cast<float>(total / n);
}

}  // namespace weft
#endif  // HWY_ONCE
