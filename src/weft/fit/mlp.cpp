#include "weft/fit/mlp.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "weft/core/error.h"
#include "weft/core/rng.h"

namespace weft {

template <typename Real>
Mlp<Real>::Mlp(const std::vector<int>& widths, OutputFunction output, uint64_t seed)
    : Mlp(NetworkWeights::initialised(widths, output, seed)) {}

template <typename Real>
Mlp<Real>::Mlp(const std::vector<int>& widths, const std::vector<bool>& prelu,
               OutputFunction output, uint64_t seed)
    : Mlp(NetworkWeights::initialised(widths, prelu, output, seed)) {}

template <typename Real>
Mlp<Real>::Mlp(const NetworkWeights& weights) : output_(weights.output) {
    if (weights.layers.empty()) throw InputError("a network needs at least one layer");
    size_t offset = 0;
    for (const NetworkLayer& src : weights.layers) {
        Layer layer;
        layer.in = src.in;
        layer.out = src.out;
        layer.prelu = src.hasPrelu();
        layer.weightOffset = offset;
        offset += static_cast<size_t>(layer.in) * layer.out;
        layer.biasOffset = offset;
        offset += layer.out;
        layer.preluOffset = offset;
        if (layer.prelu) offset += layer.out;
        layers_.push_back(layer);
    }
    params_.assign(offset, Real(0));
    for (size_t l = 0; l < layers_.size(); ++l) {
        const Layer& layer = layers_[l];
        const NetworkLayer& src = weights.layers[l];
        if (src.weight.size() != static_cast<size_t>(layer.in) * layer.out ||
            src.bias.size() != static_cast<size_t>(layer.out))
            throw std::invalid_argument("Mlp: layer sizes do not match their shape");
        std::copy(src.weight.begin(), src.weight.end(), params_.begin() + layer.weightOffset);
        std::copy(src.bias.begin(), src.bias.end(), params_.begin() + layer.biasOffset);
        std::copy(src.prelu.begin(), src.prelu.end(), params_.begin() + layer.preluOffset);
    }
}

template <typename Real>
NetworkWeights Mlp<Real>::weights() const {
    NetworkWeights net;
    net.output = output_;
    for (const Layer& layer : layers_) {
        NetworkLayer dst;
        dst.in = layer.in;
        dst.out = layer.out;
        auto range = [&](size_t offset, size_t count) {
            std::vector<float> v(count);
            for (size_t k = 0; k < count; ++k) v[k] = static_cast<float>(params_[offset + k]);
            return v;
        };
        dst.weight = range(layer.weightOffset, static_cast<size_t>(layer.in) * layer.out);
        dst.bias = range(layer.biasOffset, static_cast<size_t>(layer.out));
        if (layer.prelu) dst.prelu = range(layer.preluOffset, static_cast<size_t>(layer.out));
        net.layers.push_back(std::move(dst));
    }
    return net;
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
typename Mlp<Real>::Tape Mlp<Real>::forwardTape(const Matrix& x) const {
    if (x.rows() != inputs()) throw std::invalid_argument("Mlp::forwardTape: wrong input size");
    const size_t n = layers_.size();
    Tape tape;
    tape.inputsOf.resize(n);
    tape.preOf.resize(n);
    Matrix a = x;
    for (size_t l = 0; l < n; ++l) {
        tape.inputsOf[l] = a;
        Matrix z = preActivation(static_cast<int>(l), a);
        tape.preOf[l] = z;
        applyPrelu(static_cast<int>(l), z);
        a = std::move(z);
    }
    applyOutput(output_, a);
    tape.y = std::move(a);
    return tape;
}

template <typename Real>
void Mlp<Real>::backward(const Tape& tape, const Matrix& dy, std::vector<Real>& gradient) const {
    const Matrix& y = tape.y;
    // Through the output function: sigmoid' = y (1 - y), exp' = y.
    Matrix dz = dy;
    if (output_ == OutputFunction::Sigmoid)
        dz = dy.cwiseProduct((y.array() * (Real(1) - y.array())).matrix());
    if (output_ == OutputFunction::Exp) dz = dy.cwiseProduct(y);

    gradient.assign(params_.size(), Real(0));
    for (size_t li = layers_.size(); li-- > 0;) {
        const Layer& layer = layers_[li];
        Eigen::Map<RowMatrix> dW(gradient.data() + layer.weightOffset, layer.out, layer.in);
        Eigen::Map<Vector> db(gradient.data() + layer.biasOffset, layer.out);
        dW.noalias() = dz * tape.inputsOf[li].transpose();
        db = dz.rowwise().sum();
        if (li == 0) break;
        // dL/d(activation of the previous layer), then through its PReLU.
        Matrix da = weight(static_cast<int>(li)).transpose() * dz;
        const Layer& prev = layers_[li - 1];
        const Matrix& z = tape.preOf[li - 1];
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
}

template <typename Real>
Real Mlp<Real>::lossAndGradient(const Matrix& x, const Matrix& target, Loss loss,
                                const Vector& sampleWeights, std::vector<Real>& gradient) const {
    const Eigen::Index batch = x.cols();
    if (x.rows() != inputs() || target.rows() != outputs() || target.cols() != batch ||
        (sampleWeights.size() != 0 && sampleWeights.size() != batch))
        throw std::invalid_argument("Mlp::lossAndGradient: inconsistent shapes");
    const Tape tape = forwardTape(x);
    const Matrix& y = tape.y;
    // dL/dy for the batch-mean loss.
    Matrix dy(y.rows(), y.cols());
    Real total = 0;
    for (Eigen::Index c = 0; c < batch; ++c) {
        const Real w = sampleWeights.size() ? sampleWeights(c) : Real(1);
        for (Eigen::Index r = 0; r < y.rows(); ++r) {
            const auto [diff, dDiff] = lossResidual(loss, y(r, c), target(r, c));
            total += w * diff * diff;
            dy(r, c) = Real(2) * w * diff * dDiff / static_cast<Real>(batch);
        }
    }
    backward(tape, dy, gradient);
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

void setInputColumn(Mlp<float>::Matrix& x, Eigen::Index col, const Vec3& w) {
    x(0, col) = static_cast<float>(w.x), x(1, col) = static_cast<float>(w.y),
          x(2, col) = static_cast<float>(w.z);
}

void setInputColumn(Mlp<float>::Matrix& x, Eigen::Index col, const Vec3& wi, const Vec3& wo) {
    setInputColumn(x, col, wi);
    x(3, col) = static_cast<float>(wo.x), x(4, col) = static_cast<float>(wo.y),
          x(5, col) = static_cast<float>(wo.z);
}

template class Mlp<float>;
template class Mlp<double>;
template class Adam<float>;
template class Adam<double>;

}  // namespace weft
