// weft/fit/mlp.h — the tiny multilayer perceptrons of the neural yarn model.
//
// Paper 5.2-5.3, docs/design.md 6: fully connected layers y = W x + b, a
// channel-wise PReLU after every hidden layer (one learnable slope per
// channel, He et al. 2015), and an output function on the last layer:
// sigmoid (T network, P(T | wi)) or exp (M network, RGB radiance).
// Batches are column-major: one column per sample. Forward and backward
// passes work on whole mini-batches with Eigen; all parameters live in one
// flat vector (per layer: W row-major, then b, then the PReLU slopes) so that
// the optimiser and the model file see one array. Deterministic for a seed.
// Instantiated for float (training, inference) and double (gradient checks).
// The weights come from and go to yarn/network.h's NetworkWeights, the form
// that model.json stores and the renderer evaluates.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "weft/core/vec.h"
#include "weft/yarn/network.h"

namespace weft {

enum class Loss {
    Mse,     // mean over the batch of sum_k w_k (y_k - t_k)^2
    LogMse,  // the same on log(1 + y) and log(1 + t): tames the range of RDM values
};

// One sample's residual under a loss: the loss is diff^2 and its derivative
// with respect to y is 2 diff dDiff.
template <typename Real>
struct LossResidual {
    Real diff, dDiff;
};
template <typename Real>
LossResidual<Real> lossResidual(Loss loss, Real y, Real target) {
    if (loss == Loss::LogMse) return {std::log1p(y) - std::log1p(target), Real(1) / (Real(1) + y)};
    return {y - target, Real(1)};
}

template <typename Real>
class Mlp {
public:
    using Matrix = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic>;
    using Vector = Eigen::Matrix<Real, Eigen::Dynamic, 1>;
    using RowMatrix = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

    struct Layer {
        int in = 0, out = 0;
        bool prelu = false;
        size_t weightOffset = 0, biasOffset = 0, preluOffset = 0;
    };

    Mlp() = default;
    // widths = {inputs, hidden..., outputs}; PReLU after every hidden layer;
    // initialised by NetworkWeights::initialised (PyTorch's Linear default).
    Mlp(const std::vector<int>& widths, OutputFunction output, uint64_t seed);
    // The same with an explicit PReLU flag per layer (size widths.size() - 1).
    Mlp(const std::vector<int>& widths, const std::vector<bool>& prelu, OutputFunction output,
        uint64_t seed);
    // A copy of stored weights (a model's network), and back.
    explicit Mlp(const NetworkWeights& weights);
    NetworkWeights weights() const;

    const std::vector<Layer>& layers() const { return layers_; }
    OutputFunction output() const { return output_; }
    int inputs() const { return layers_.front().in; }
    int outputs() const { return layers_.back().out; }
    std::vector<int> widths() const;

    std::vector<Real>& parameters() { return params_; }
    const std::vector<Real>& parameters() const { return params_; }

    // Views of one layer's parameters (W is out x in).
    Eigen::Map<const RowMatrix> weight(int layer) const;
    Eigen::Map<const Vector> bias(int layer) const;
    Eigen::Map<const Vector> preluSlopes(int layer) const;  // size 0 without PReLU
    Eigen::Map<RowMatrix> weight(int layer);
    Eigen::Map<Vector> bias(int layer);
    Eigen::Map<Vector> preluSlopes(int layer);

    // y (outputs x batch) for x (inputs x batch).
    Matrix forward(const Matrix& x) const;

    // Loss over the batch (mean over samples) and its gradient with respect
    // to parameters() (resized and overwritten). `sampleWeights` (size batch)
    // may be empty for uniform weights.
    Real lossAndGradient(const Matrix& x, const Matrix& target, Loss loss,
                         const Vector& sampleWeights, std::vector<Real>& gradient) const;

    // The two halves of lossAndGradient, for losses on a function of the
    // outputs (a colour-conditioned head): the forward pass with what the
    // backward pass needs, and the gradient with respect to parameters()
    // (resized and overwritten) for dL/dy (outputs x batch, after the output function).
    struct Tape {
        std::vector<Matrix> inputsOf, preOf;  // per layer: its input and pre-activation
        Matrix y;                             // outputs x batch
    };
    Tape forwardTape(const Matrix& x) const;
    void backward(const Tape& tape, const Matrix& dy, std::vector<Real>& gradient) const;

private:
    // W x + b of layer l, and the layer's PReLU (in place; nothing for the last layer).
    Matrix preActivation(int l, const Matrix& a) const;
    void applyPrelu(int l, Matrix& z) const;

    std::vector<Layer> layers_;
    OutputFunction output_ = OutputFunction::Identity;
    std::vector<Real> params_;
};

// Column `col` of a float input batch: a direction (T network) or a pair
// (wi, wo) (M network), in the yarn frame.
void setInputColumn(Mlp<float>::Matrix& x, Eigen::Index col, const Vec3& w);
void setInputColumn(Mlp<float>::Matrix& x, Eigen::Index col, const Vec3& wi, const Vec3& wo);

// Adam (Kingma & Ba 2015) with bias correction, over a flat parameter vector.
template <typename Real>
class Adam {
public:
    explicit Adam(size_t size, double learningRate = 1e-3, double beta1 = 0.9,
                  double beta2 = 0.999, double epsilon = 1e-8);

    void setLearningRate(double lr) { learningRate_ = lr; }
    double learningRate() const { return learningRate_; }
    int64_t steps() const { return step_; }
    void step(std::vector<Real>& params, const std::vector<Real>& gradient);

private:
    double learningRate_, beta1_, beta2_, epsilon_;
    int64_t step_ = 0;
    std::vector<double> m_, v_;
};

extern template class Mlp<float>;
extern template class Mlp<double>;
extern template class Adam<float>;
extern template class Adam<double>;

}  // namespace weft
