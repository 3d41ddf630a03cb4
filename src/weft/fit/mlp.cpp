#include "weft/fit/mlp.h"

#include <cmath>
#include <stdexcept>

#include "weft/core/error.h"
#include "weft/core/rng.h"

namespace weft {

std::string toString(OutputFunction f) {
    switch (f) {
        case OutputFunction::Identity: return "identity";
        case OutputFunction::Sigmoid: return "sigmoid";
        case OutputFunction::Exp: return "exp";
    }
    return "identity";
}

OutputFunction outputFunctionFromString(const std::string& name) {
    if (name == "identity") return OutputFunction::Identity;
    if (name == "sigmoid") return OutputFunction::Sigmoid;
    if (name == "exp") return OutputFunction::Exp;
    throw InputError("unknown output function \"" + name + "\" (allowed: identity, sigmoid, exp)");
}

namespace {

std::vector<bool> preluAfterHiddenLayers(size_t widthCount) {
    std::vector<bool> prelu(widthCount < 2 ? 0 : widthCount - 1, true);
    if (!prelu.empty()) prelu.back() = false;
    return prelu;
}

}  // namespace

template <typename Real>
Mlp<Real>::Mlp(const std::vector<int>& widths, OutputFunction output, uint64_t seed)
    : Mlp(widths, preluAfterHiddenLayers(widths.size()), output, seed) {}

template <typename Real>
Mlp<Real>::Mlp(const std::vector<int>& widths, const std::vector<bool>& prelu,
               OutputFunction output, uint64_t seed)
    : output_(output) {
    if (widths.size() < 2) throw InputError("a network needs at least an input and an output width");
    if (prelu.size() + 1 != widths.size())
        throw std::invalid_argument("Mlp: one PReLU flag per layer expected");
    for (int w : widths)
        if (w < 1 || w > 4096)
            throw InputError("layer width " + std::to_string(w) + " is out of range: allowed [1, 4096]");
    size_t offset = 0;
    for (size_t l = 0; l + 1 < widths.size(); ++l) {
        Layer layer;
        layer.in = widths[l];
        layer.out = widths[l + 1];
        layer.prelu = prelu[l];
        layer.weightOffset = offset;
        offset += static_cast<size_t>(layer.in) * layer.out;
        layer.biasOffset = offset;
        offset += layer.out;
        layer.preluOffset = offset;
        if (layer.prelu) offset += layer.out;
        layers_.push_back(layer);
    }
    params_.assign(offset, Real(0));
    Rng rng(0x4d4c50, seed);
    for (const Layer& layer : layers_) {
        const double bound = 1.0 / std::sqrt(static_cast<double>(layer.in));
        for (size_t k = layer.weightOffset; k < layer.preluOffset; ++k)
            params_[k] = static_cast<Real>(bound * (2.0 * rng.uniform() - 1.0));
        if (layer.prelu)
            for (int k = 0; k < layer.out; ++k) params_[layer.preluOffset + k] = Real(0.25);
    }
}

template <typename Real>
std::vector<int> Mlp<Real>::widths() const {
    std::vector<int> w = {layers_.front().in};
    for (const Layer& l : layers_) w.push_back(l.out);
    return w;
}

template <typename Real>
Eigen::Map<const typename Mlp<Real>::RowMatrix> Mlp<Real>::weight(int l) const {
    const Layer& layer = layers_[l];
    return {params_.data() + layer.weightOffset, layer.out, layer.in};
}
template <typename Real>
Eigen::Map<const typename Mlp<Real>::Vector> Mlp<Real>::bias(int l) const {
    return {params_.data() + layers_[l].biasOffset, layers_[l].out};
}
template <typename Real>
Eigen::Map<const typename Mlp<Real>::Vector> Mlp<Real>::preluSlopes(int l) const {
    return {params_.data() + layers_[l].preluOffset, layers_[l].prelu ? layers_[l].out : 0};
}
template <typename Real>
Eigen::Map<typename Mlp<Real>::RowMatrix> Mlp<Real>::weight(int l) {
    const Layer& layer = layers_[l];
    return {params_.data() + layer.weightOffset, layer.out, layer.in};
}
template <typename Real>
Eigen::Map<typename Mlp<Real>::Vector> Mlp<Real>::bias(int l) {
    return {params_.data() + layers_[l].biasOffset, layers_[l].out};
}
template <typename Real>
Eigen::Map<typename Mlp<Real>::Vector> Mlp<Real>::preluSlopes(int l) {
    return {params_.data() + layers_[l].preluOffset, layers_[l].prelu ? layers_[l].out : 0};
}

namespace {

template <typename Matrix>
void applyOutput(OutputFunction f, Matrix& z) {
    using Real = typename Matrix::Scalar;
    if (f == OutputFunction::Sigmoid) z = (Real(1) + (-z.array()).exp()).inverse().matrix();
    if (f == OutputFunction::Exp) z = z.array().exp().matrix();
}

}  // namespace

template <typename Real>
typename Mlp<Real>::Matrix Mlp<Real>::preActivation(int l, const Matrix& a) const {
    Matrix z = weight(l) * a;
    z.colwise() += bias(l);
    return z;
}

template <typename Real>
void Mlp<Real>::applyPrelu(int l, Matrix& z) const {
    if (!layers_[l].prelu) return;
    const auto slopes = preluSlopes(l);
    for (Eigen::Index c = 0; c < z.cols(); ++c)
        for (Eigen::Index r = 0; r < z.rows(); ++r)
            if (z(r, c) < 0) z(r, c) *= slopes(r);
}

template <typename Real>
typename Mlp<Real>::Matrix Mlp<Real>::forward(const Matrix& x) const {
    if (x.rows() != inputs()) throw std::invalid_argument("Mlp::forward: wrong input size");
    Matrix a = x;
    for (size_t l = 0; l < layers_.size(); ++l) {
        Matrix z = preActivation(static_cast<int>(l), a);
        applyPrelu(static_cast<int>(l), z);
        a = std::move(z);
    }
    applyOutput(output_, a);
    return a;
}

template <typename Real>
Real Mlp<Real>::lossAndGradient(const Matrix& x, const Matrix& target, Loss loss,
                                const Vector& sampleWeights, std::vector<Real>& gradient) const {
    const Eigen::Index batch = x.cols();
    if (x.rows() != inputs() || target.rows() != outputs() || target.cols() != batch ||
        (sampleWeights.size() != 0 && sampleWeights.size() != batch))
        throw std::invalid_argument("Mlp::lossAndGradient: inconsistent shapes");
    // Forward pass, keeping every layer's input activation and pre-activation.
    const size_t n = layers_.size();
    std::vector<Matrix> inputsOf(n), preOf(n);
    Matrix a = x;
    for (size_t l = 0; l < n; ++l) {
        inputsOf[l] = a;
        Matrix z = preActivation(static_cast<int>(l), a);
        preOf[l] = z;
        applyPrelu(static_cast<int>(l), z);
        a = std::move(z);
    }
    Matrix y = a;
    applyOutput(output_, y);

    // dL/dy for the batch-mean loss.
    Matrix dy(y.rows(), y.cols());
    Real total = 0;
    for (Eigen::Index c = 0; c < batch; ++c) {
        const Real w = sampleWeights.size() ? sampleWeights(c) : Real(1);
        for (Eigen::Index r = 0; r < y.rows(); ++r) {
            Real diff, dDiff;
            if (loss == Loss::LogMse) {
                diff = std::log1p(y(r, c)) - std::log1p(target(r, c));
                dDiff = Real(1) / (Real(1) + y(r, c));
            } else {
                diff = y(r, c) - target(r, c);
                dDiff = Real(1);
            }
            total += w * diff * diff;
            dy(r, c) = Real(2) * w * diff * dDiff / static_cast<Real>(batch);
        }
    }
    // Through the output function: sigmoid' = y (1 - y), exp' = y.
    Matrix dz = dy;
    if (output_ == OutputFunction::Sigmoid) dz = dy.cwiseProduct((y.array() * (Real(1) - y.array())).matrix());
    if (output_ == OutputFunction::Exp) dz = dy.cwiseProduct(y);

    gradient.assign(params_.size(), Real(0));
    for (size_t li = n; li-- > 0;) {
        const Layer& layer = layers_[li];
        Eigen::Map<RowMatrix> dW(gradient.data() + layer.weightOffset, layer.out, layer.in);
        Eigen::Map<Vector> db(gradient.data() + layer.biasOffset, layer.out);
        dW.noalias() = dz * inputsOf[li].transpose();
        db = dz.rowwise().sum();
        if (li == 0) break;
        // dL/d(activation of the previous layer), then through its PReLU.
        Matrix da = weight(static_cast<int>(li)).transpose() * dz;
        const Layer& prev = layers_[li - 1];
        const Matrix& z = preOf[li - 1];
        if (prev.prelu) {
            const auto slopes = preluSlopes(static_cast<int>(li - 1));
            Eigen::Map<Vector> dSlopes(gradient.data() + prev.preluOffset, prev.out);
            dSlopes.setZero();
            for (Eigen::Index c = 0; c < z.cols(); ++c)
                for (Eigen::Index r = 0; r < z.rows(); ++r)
                    if (z(r, c) < 0) {
                        dSlopes(r) += da(r, c) * z(r, c);
                        da(r, c) *= slopes(r);
                    }
        }
        dz = std::move(da);
    }
    return total / static_cast<Real>(batch);
}

template <typename Real>
Adam<Real>::Adam(size_t size, double learningRate, double beta1, double beta2, double epsilon)
    : learningRate_(learningRate), beta1_(beta1), beta2_(beta2), epsilon_(epsilon),
      m_(size, 0.0), v_(size, 0.0) {}

template <typename Real>
void Adam<Real>::step(std::vector<Real>& params, const std::vector<Real>& gradient) {
    if (params.size() != m_.size() || gradient.size() != m_.size())
        throw std::invalid_argument("Adam::step: size mismatch");
    ++step_;
    const double c1 = 1.0 - std::pow(beta1_, static_cast<double>(step_));
    const double c2 = 1.0 - std::pow(beta2_, static_cast<double>(step_));
    for (size_t k = 0; k < params.size(); ++k) {
        const double g = gradient[k];
        m_[k] = beta1_ * m_[k] + (1.0 - beta1_) * g;
        v_[k] = beta2_ * v_[k] + (1.0 - beta2_) * g * g;
        params[k] -= static_cast<Real>(learningRate_ * (m_[k] / c1) / (std::sqrt(v_[k] / c2) + epsilon_));
    }
}

template class Mlp<float>;
template class Mlp<double>;
template class Adam<float>;
template class Adam<double>;

}  // namespace weft
