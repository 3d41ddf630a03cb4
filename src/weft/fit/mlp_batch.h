// weft/fit/mlp_batch.h — the training passes of an Mlp<float> on one chunk of
// samples, in float32 SIMD without touching the heap.
//
// Mlp<Real>::lossAndGradient (mlp.h) is the plain Eigen form of the same
// maths: it allocates a matrix per layer and step, branches on the sign of
// every PReLU input and, in a portable build, runs Eigen's SSE2 code; a fit
// spent most of its time there (bench/results/trainer.md). MlpBatch keeps
// one workspace per chunk, allocated once, and runs the passes through
// Google Highway with run-time dispatch (AVX2 + FMA or AVX-512 where the CPU
// has them; yarn/fixed_mlp.h explains the choice):
//   - a chunk is stored by rows (BatchRows): row r holds value r of every
//     sample, so each vector lane is one sample and a layer is
//     z[o] = b[o] + sum_i W[o][i] a[i] with a broadcast weight per FMA;
//   - every sample goes through the same operations in the same order in
//     every kernel, and every sum over samples (a weight's gradient) keeps
//     kMlpSampleGroup partial sums (sample k in sum k mod 16, in order) added
//     in one fixed tree at the end: the kernels with FMA (AVX2, AVX-512) give
//     the same bits, so a fit does not depend on which of them the CPU runs
//     (those without FMA, SSE4 and older, round differently);
//   - PReLU as max(z, 0) + slope min(z, 0), its backward pass with a select:
//     no branches;
//   - the exp output saturates at e^80 (as the renderer's, fixed_mlp.h).
// mlp_batch_test holds the gradient to Mlp<double>'s (itself checked against
// finite differences) for every instruction set the CPU runs.
#pragma once

#include <hwy/aligned_allocator.h>

#include <cstdint>
#include <vector>

#include "weft/core/vec.h"
#include "weft/fit/mlp.h"

namespace weft {

// Sums over the samples of a chunk keep this many partial sums (above); rows
// are padded to a multiple of it.
constexpr int kMlpSampleGroup = 16;

// A chunk of samples stored by rows: `rows` rows of `stride` floats (the
// capacity rounded up to kMlpSampleGroup), 64-byte aligned, zero-initialised.
class BatchRows {
  public:
    BatchRows() = default;
    BatchRows(int rows, int capacity);

    int rows() const { return rows_; }
    int capacity() const { return capacity_; }
    int stride() const { return stride_; }
    float* row(int r) { return data_.get() + static_cast<size_t>(r) * stride_; }
    const float* row(int r) const { return data_.get() + static_cast<size_t>(r) * stride_; }
    float& operator()(int r, int k) { return row(r)[k]; }
    float operator()(int r, int k) const { return row(r)[k]; }

  private:
    int rows_ = 0, capacity_ = 0, stride_ = 0;
    hwy::AlignedFreeUniquePtr<float[]> data_;
};

// Sample k of a chunk: a direction (T network inputs) or a pair (wi, wo)
// (M network inputs), in the yarn frame.
void setInputColumn(BatchRows& x, int k, const Vec3& w);
void setInputColumn(BatchRows& x, int k, const Vec3& wi, const Vec3& wo);

// The passes' loops over samples, compiled once per instruction set
// (mlp_batch.cpp). Rows are `stride` floats apart; n (a multiple of
// kMlpSampleGroup) samples are processed. A weight w(r, j) is at
// w[r * rowStep + j * colStep].
struct MlpBatchKernel {
    // z[r] = (bias ? bias[r] : 0) + sum_j w(r, j) a[j], for r < rows, j < cols.
    void (*dense)(const float* w, int rowStep, int colStep, const float* bias, int rows, int cols,
                  const float* a, float* z, int stride, int n) = nullptr;
    // a[r] = max(z[r], 0) + slope[r] min(z[r], 0).
    void (*prelu)(const float* slope, int rows, const float* z, float* a, int stride,
                  int n) = nullptr;
    // Through a PReLU backwards: dSlope[r] = sum_k da[r][k] min(z[r][k], 0),
    // then da[r][k] *= slope[r] where z[r][k] < 0.
    void (*preluBackward)(const float* slope, int rows, const float* z, float* da, float* dSlope,
                          int stride, int n) = nullptr;
    // dW[r * cols + j] = sum_k dz[r][k] a[j][k], db[r] = sum_k dz[r][k].
    void (*weightGradient)(const float* dz, int rows, const float* a, int cols, float* dW,
                           float* db, int stride, int n) = nullptr;
    // y = f(z) in place, for the network's output function f.
    void (*output)(OutputFunction f, float* y, int rows, int stride, int n) = nullptr;
    // dz = dy f'(z) from y = f(z), in place in dy.
    void (*outputBackward)(OutputFunction f, const float* y, float* dy, int rows, int stride,
                           int n) = nullptr;
    // The loss's residual per entry (mlp.h, lossResidual): diff[r][k], and
    // dy[r][k] = scale diff dDiff (the caller zeroes what lies past its samples).
    void (*residual)(Loss loss, const float* y, const float* target, int targetStride, float* diff,
                     float* dy, float scale, int rows, int stride, int n) = nullptr;
    const char* target = "none";    // Highway's name: "AVX3", "AVX2", "SSE4", ...
    bool fusedMultiplyAdd = false;  // one rounding per multiply-add (AVX2, AVX-512, NEON)
};

// The kernel of the best instruction set that this CPU runs, and every
// kernel it runs (best first), for the tests.
MlpBatchKernel mlpBatchKernel();
std::vector<MlpBatchKernel> mlpBatchKernels();

class MlpBatch {
  public:
    // Passes of `net` on chunks of up to `capacity` samples. The parameters
    // are read from net at every pass (the optimiser changes them between
    // steps); net must outlive this object and keep its shape.
    MlpBatch(const Mlp<float>& net, int capacity, const MlpBatchKernel& kernel = mlpBatchKernel());

    int capacity() const { return capacity_; }
    const MlpBatchKernel& kernel() const { return kernel_; }

    // The outputs (after the output function) for the first n samples of
    // x's first net.inputs() rows (later rows, such as a colour that only
    // the loss reads, are ignored).
    void forward(const BatchRows& x, int n);
    const float* output(int row) const { return acts_.back().row(row); }

    // After forward(): the gradient of a loss with respect to parameters()
    // (resized and overwritten), given dL/dy in outputGradient(row)[0, n)
    // (the caller writes it; entries from n on are ignored).
    float* outputGradient(int row) { return dOut_.row(row); }
    void backward(std::vector<float>& gradient);

    // forward(), then the batch-mean loss of `loss` against target's first
    // n samples (row k = output k), returned, and its gradient (backward()).
    float lossAndGradient(const BatchRows& x, const BatchRows& target, int n, Loss loss,
                          std::vector<float>& gradient);

  private:
    int padded() const;  // n_ rounded up to kMlpSampleGroup

    const Mlp<float>* net_;
    MlpBatchKernel kernel_;
    int capacity_, n_ = 0;
    std::vector<BatchRows> acts_;  // acts_[l]: input of layer l; back(): the outputs
    std::vector<BatchRows> pre_;   // pre_[l]: pre-activation of layer l (hidden layers)
    BatchRows dOut_, dA_, dB_;     // dL/dy, and two buffers of dL/d(activations)
    BatchRows diff_;               // the loss's residuals
};

}  // namespace weft
