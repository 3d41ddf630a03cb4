#include "weft/yarn/dual_scattering.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/quadrature.h"
#include "weft/core/sampling.h"
#include "weft/yarn/sphere_rule.h"

namespace weft {

namespace {

constexpr double kInvTwoPi = 0.5 * kInvPi;
// a_f above this makes A_b and sigma_b blow up (1 - a_f^2 in denominators).
constexpr double kMaxForwardEnergy = 0.99;
// Lobe widths are clamped to this range (radians) for the normaliser table.
constexpr double kMinWidth = 0.05 * kPi / 180.0, kMaxWidth = 10.0;

// Z(mu, s) = integral_{-pi/2}^{pi/2} exp(-(t - mu)^2 / (2 s^2)) cos^2 t dt for
// any width s: the closed form on the whole line,
//     Z_line = sqrt(2 pi) s (1 + cos(2 mu) exp(-2 s^2)) / 2,
// times the tabulated share Z / Z_line that lies within [-pi/2, pi/2]
// (bilinear in |mu| and log s; one table for the process). The lobes of the
// baseline have widths that vary with wo (n_f), so LongitudinalGaussian's
// per-width tables do not fit.
class WidthFamily {
  public:
    static const WidthFamily& instance() {
        static const WidthFamily family;
        return family;
    }

    // Z_line for cos2Mu = cos(2 mu).
    static double lineIntegral(double cos2Mu, double s) {
        return std::sqrt(kTwoPi) * s * 0.5 * (1.0 + cos2Mu * std::exp(-2.0 * s * s));
    }
    static double byQuadrature(double mu, double s) {
        const double a = std::max(-kHalfPi, mu - 12.0 * s), b = std::min(kHalfPi, mu + 12.0 * s);
        if (!(b > a)) return 0.0;
        std::vector<double> edges, x, w;
        quadrature::uniformEdges(a, b, 48, &edges);
        quadrature::panelRule(edges, &x, &w);
        double sum = 0;
        for (size_t k = 0; k < x.size(); ++k) {
            const double c = std::cos(x[k]);
            sum += w[k] * std::exp(-sqr(x[k] - mu) / (2.0 * s * s)) * c * c;
        }
        return sum;
    }

    // cos2Mu = cos(2 mu), which a caller with many widths for one mu computes once.
    double normalization(double mu, double cos2Mu, double s) const {
        const double m = std::min(std::abs(mu), kHalfPi) / kHalfPi * (kMu - 1);
        const double l = (std::log(s) - logMin_) / (logMax_ - logMin_) * (kWidths - 1);
        const int i = std::min(static_cast<int>(m), kMu - 2);
        const int j = std::clamp(static_cast<int>(l), 0, kWidths - 2);
        const double fm = m - i, fl = std::clamp(l - j, 0.0, 1.0);
        auto at = [&](int a, int b) { return share_[static_cast<size_t>(a) * kWidths + b]; };
        const double share = (1 - fm) * ((1 - fl) * at(i, j) + fl * at(i, j + 1)) +
                             fm * ((1 - fl) * at(i + 1, j) + fl * at(i + 1, j + 1));
        return lineIntegral(cos2Mu, s) * share;
    }

    size_t memoryBytes() const { return sizeof(*this) + share_.size() * sizeof(double); }

  private:
    static constexpr int kMu = 129, kWidths = 65;

    WidthFamily() : logMin_(std::log(kMinWidth)), logMax_(std::log(kMaxWidth)) {
        share_.resize(static_cast<size_t>(kMu) * kWidths);
        for (int i = 0; i < kMu; ++i) {
            const double mu = kHalfPi * i / (kMu - 1);
            for (int j = 0; j < kWidths; ++j) {
                const double s = std::exp(logMin_ + (logMax_ - logMin_) * j / (kWidths - 1));
                share_[static_cast<size_t>(i) * kWidths + j] =
                    byQuadrature(mu, s) / lineIntegral(std::cos(2.0 * mu), s);
            }
        }
    }

    double logMin_, logMax_;
    std::vector<double> share_;
};

// g(theta; mu, s), normalised against cos^2 on [-pi/2, pi/2]; cos2Mu = cos(2 mu).
double cosSquaredGaussian(double theta, double mu, double cos2Mu, double s) {
    s = std::clamp(s, kMinWidth, kMaxWidth);
    return std::exp(-sqr(theta - mu) / (2.0 * s * s)) /
           WidthFamily::instance().normalization(mu, cos2Mu, s);
}

// The share of a von Mises lobe within pi/2 of its mean.
double forwardShare(const VonMises& lobe) {
    std::vector<double> edges, x, w;
    quadrature::uniformEdges(-kHalfPi, kHalfPi, 64, &edges);
    quadrature::panelRule(edges, &x, &w);
    double sum = 0;
    for (size_t k = 0; k < x.size(); ++k) sum += w[k] * lobe.pdf(x[k]);
    return std::min(sum, 1.0);
}

// The energy clamp's grid over the upper hemisphere of wi (yarn frame):
// a = asin(wi.x) in [-pi/2, pi/2], b = atan2(wi.z, wi.y) in [0, pi], both with
// Chebyshev-spaced nodes (x_k = -cos(pi k / (n - 1)) on [-1, 1]), dense near
// the ends: near grazing (b -> 0, pi) and along the axis the albedo changes fast.
constexpr int kClampA = 13, kClampB = 9;

double chebyshevNode(int k, int n) { return -std::cos(kPi * k / (n - 1)); }
// The fractional index of x in [-1, 1] among those nodes.
double chebyshevIndex(double x, int n) {
    return std::acos(-std::clamp(x, -1.0, 1.0)) / kPi * (n - 1);
}

Vec3 clampNodeDirection(int ia, int ib) {
    const double a = kHalfPi * chebyshevNode(ia, kClampA);
    const double b = kHalfPi * (1 + chebyshevNode(ib, kClampB));
    return {std::sin(a), std::cos(a) * std::cos(b), std::max(0.0, std::cos(a) * std::sin(b))};
}

}  // namespace

void DualScatteringOptions::validate() const {
    auto check = [](double v, const char* name) {
        if (!(v >= 0.0 && v <= 1.0))
            throw InputError(std::string("dual-scattering ") + name + " " + std::to_string(v) +
                             " is out of range: allowed [0, 1]");
    };
    check(forwardScale, "d_f");
    check(backScale, "d_b");
}

DualScatteringBsdf::DualScatteringBsdf(const FiberParams& fiber, const PlyParams& ply,
                                       const DualScatteringOptions& options)
    : fiber_(fiber),
      options_((options.validate(), options)),
      frame_(SurfaceFiberFrame::fromTiltDeg(SurfaceFiberFrame::tiltDegOfTwist(ply.twist))),
      forwardShareTT_(forwardShare(VonMises(1.0 / sqr(radians(fiber.gammaTTDeg))))),
      fibersPerChord_((ply.validate(), 4.0 / kPi * std::sqrt(ply.fibers * ply.density))),
      betaR_(radians(fiber.betaRDeg)),
      betaTT_(radians(fiber.betaTTDeg)),
      // Wide enough for the global lobe halfway through the ply.
      wideLobe_(std::clamp(
          std::sqrt(sqr(std::max(betaR_, betaTT_)) + 0.5 * fibersPerChord_ * sqr(betaTT_)),
          radians(10.0), kHalfPi)) {
    if (options_.energyClamp) buildEnergyClamp();
}

double DualScatteringBsdf::fibersCrossed(const Vec3& wo) const {
    const double perp = std::sqrt(wo.y * wo.y + wo.z * wo.z);
    if (!(perp > 0) || wo.z >= 0) return 0.0;
    return fibersPerChord_ * (-wo.z / perp);
}

DualScatteringBsdf::Incident DualScatteringBsdf::incident(const Vec3& upperWi) const {
    Incident in;
    in.flip = false;
    in.upper = upperWi;
    in.fiber = fiber_.incident(frame_.toLocal(upperWi));
    in.thetaI = in.fiber.angles.theta;
    in.cos2Mu = std::cos(2.0 * in.thetaI);  // mu = -theta_i
    const double w = forwardShareTT_, db = options_.backScale;
    const double betaR2 = betaR_ * betaR_, betaTT2 = betaTT_ * betaTT_;
    for (int c = 0; c < 3; ++c) {
        const double f = in.fiber.fresnel[c], ctt = fiber_.params().cTT[c];
        const double r = 0.5 * f, ttForward = (1 - f) * ctt * w,
                     ttBackward = (1 - f) * ctt * (1 - w);
        Channel& ch = in.channel[c];
        ch.fresnel = f;
        ch.forward = std::min(r + ttForward, kMaxForwardEnergy);
        ch.backward = r + ttBackward;
        // Lobe variances averaged with the lobes' energies as weights.
        ch.betaForward2 =
            r + ttForward > 0 ? (r * betaR2 + ttForward * betaTT2) / (r + ttForward) : betaR2;
        const double betaBackward2 =
            ch.backward > 0 ? (r * betaR2 + ttBackward * betaTT2) / ch.backward : betaR2;
        const double af2 = ch.forward * ch.forward, ab = ch.backward, ab3 = ab * ab * ab;
        const double rest = 1 - af2;
        ch.backAmplitude = ab * af2 / rest + ab3 * af2 / (rest * rest * rest);
        // sigma_b in Zinke's theta_h units (half the longitudinal widths), then
        // twice that in theta_o units.
        const double bf = 0.5 * std::sqrt(ch.betaForward2), bb = 0.5 * std::sqrt(betaBackward2);
        const double denominator = ab + ab3 * (2 * bf + 3 * bb);
        const double sigma = denominator > 0 ? (1 + db * af2) *
                                                   (ab * std::sqrt(2 * bf * bf + bb * bb) +
                                                    ab3 * std::sqrt(2 * bf * bf + 3 * bb * bb)) /
                                                   denominator
                                             : 0.0;
        ch.backWidth = std::clamp(2 * sigma, kMinWidth, kMaxWidth);
    }
    in.scale = clampScale(upperWi);
    return in;
}

DualScatteringBsdf::Parts DualScatteringBsdf::partsUpper(const Incident& in, const Vec3& wo) const {
    Parts parts;
    const FiberBcsdf::Angles out = FiberBcsdf::anglesOf(frame_.toLocal(wo));
    if (out.cosTheta <= 0) return parts;
    const Rgb single = fiber_.evalPrepared(in.fiber, out);  // cos theta_o included
    const double n = fibersCrossed(wo);
    const double direct = 1 - std::min(n, 1.0);
    const double df = options_.forwardScale, db = options_.backScale;
    const double mu = -in.thetaI, cos2Mu = in.cos2Mu, thetaO = out.theta, w = forwardShareTT_;
    for (int c = 0; c < 3; ++c) {
        const Channel& ch = in.channel[c];
        double multiple = 0;
        if (direct > 0) {
            parts.single[c] = direct * single[c];
            const double back =
                ch.backAmplitude * cosSquaredGaussian(thetaO, mu, cos2Mu, ch.backWidth) * kInvTwoPi;
            multiple += direct * db * back * out.cosTheta;
        }
        if (direct < 1) {
            const double transmitted = direct + (1 - direct) * df * std::pow(ch.forward, n);
            const double spread = n * ch.betaForward2;
            const double global =
                ch.fresnel * cosSquaredGaussian(thetaO, mu, cos2Mu, std::sqrt(betaR_ * betaR_ + spread)) *
                    kInvTwoPi +
                (1 - ch.fresnel) * fiber_.params().cTT[c] *
                    cosSquaredGaussian(thetaO, mu, cos2Mu, std::sqrt(betaTT_ * betaTT_ + spread)) * w *
                    kInvPi;
            const double back =
                ch.backAmplitude *
                cosSquaredGaussian(thetaO, mu, cos2Mu,
                                   std::sqrt(ch.backWidth * ch.backWidth + spread)) *
                kInvTwoPi;
            multiple += (transmitted - direct) * df * (global + kPi * db * back) * out.cosTheta;
        }
        parts.multiple[c] = multiple;
    }
    return parts;
}

Rgb DualScatteringBsdf::evalUpper(const Incident& in, const Vec3& wo) const {
    const Parts p = partsUpper(in, wo);
    return p.single + p.multiple;
}

DualScatteringBsdf::Parts DualScatteringBsdf::parts(const Vec3& wi, const Vec3& wo) const {
    const bool flip = wi.z < 0;
    const Incident in = incident(flip ? mirrored(wi) : wi);
    Parts p = partsUpper(in, flip ? mirrored(wo) : wo);
    p.single *= in.scale;
    p.multiple *= in.scale;
    return p;
}

double DualScatteringBsdf::pdfUpper(const Incident& in, const Vec3& wo) const {
    const FiberBcsdf::Angles out = FiberBcsdf::anglesOf(frame_.toLocal(wo));
    double density = kPickUniform * uniformSpherePdf();
    if (out.cosTheta <= 0) return density;
    density += kPickSingle * fiber_.evalPdfPrepared(in.fiber, out).pdf;
    // theta from g cos^2 and a uniform azimuth: g cos(theta) / (2 pi) per steradian.
    density += kPickWide * wideLobe_.eval(out.theta, -in.thetaI) * out.cosTheta * kInvTwoPi;
    return density;
}

void DualScatteringBsdf::prepare(const Vec3& wi, BsdfIncident& in) const {
    const bool flip = wi.z < 0;
    Incident p = incident(flip ? mirrored(wi) : wi);
    p.flip = flip;
    in.emplace(wi, p);
}

BsdfEval DualScatteringBsdf::evalPdf(const BsdfIncident& in, const Vec3& wo) const {
    const Incident& p = in.get<Incident>();
    const Vec3 o = p.flip ? mirrored(wo) : wo;
    return {evalUpper(p, o) * p.scale, pdfUpper(p, o)};
}

BsdfSample DualScatteringBsdf::sample(const BsdfIncident& in, const BsdfSampleInput& u,
                                      Rng& rng) const {
    const Incident& p = in.get<Incident>();
    Vec3 o;
    int lobe;
    if (u[0] < kPickSingle) {
        // The fiber's own sampler in the surface fiber frame; the rest of u[0]
        // picks its lobe.
        BsdfIncident fiberIn;
        fiber_.prepare(frame_.toLocal(p.upper), fiberIn);
        const double uLobe = std::min(u[0] / kPickSingle, kOneMinusEpsilon);
        const BsdfSample s = fiber_.sample(fiberIn, {uLobe, u[1], u[2]}, rng);
        if (!s.valid()) return {};
        o = frame_.fromLocal(s.wo);
        lobe = kLobeSingle;
    } else if (u[0] < kPickSingle + kPickWide) {
        const double thetaO = wideLobe_.sample(-p.thetaI, u[1], rng);
        o = frame_.direction(thetaO, kPi * (2 * u[2] - 1));
        lobe = kLobeWide;
    } else {
        o = sampleUniformSphere(u[1], u[2]);
        lobe = kLobeUniform;
    }
    const Vec3 wo = p.flip ? mirrored(o) : o;
    return BsdfSample::fromEval(wo, evalPdf(in, wo), lobe);
}

Rgb DualScatteringBsdf::clampScale(const Vec3& wi) const {
    if (clamp_.empty()) return Rgb(1.0);
    const Vec3 upper = wi.z < 0 ? mirrored(wi) : wi;
    const double a = chebyshevIndex(std::asin(std::clamp(upper.x, -1.0, 1.0)) / kHalfPi, kClampA);
    const double b = chebyshevIndex(std::atan2(upper.z, upper.y) / kHalfPi - 1, kClampB);
    const int i = std::clamp(static_cast<int>(a), 0, kClampA - 2);
    const int j = std::clamp(static_cast<int>(b), 0, kClampB - 2);
    const double fa = std::clamp(a - i, 0.0, 1.0), fb = std::clamp(b - j, 0.0, 1.0);
    auto at = [&](int x, int y) { return clamp_[static_cast<size_t>(x) * kClampB + y]; };
    return at(i, j) * ((1 - fa) * (1 - fb)) + at(i, j + 1) * ((1 - fa) * fb) +
           at(i + 1, j) * (fa * (1 - fb)) + at(i + 1, j + 1) * (fa * fb);
}

void DualScatteringBsdf::buildEnergyClamp() {
    constexpr int kNodes = kClampA * kClampB;
    std::vector<Rgb> scale(static_cast<size_t>(kNodes), Rgb(1.0));
    // A half turn about n, (x, y, z) -> (-x, -y, z), maps the ply (its fibers
    // are lines, whichever way along) and so the BSDF onto itself: a -> -a,
    // b -> pi - b, i.e. node k -> node kNodes - 1 - k (the Chebyshev nodes are
    // symmetric). Half the nodes are computed (tested: albedo(wi) equals
    // albedo of the turned wi).
    tbb::parallel_for(0, (kNodes + 1) / 2, [&](int node) {
        const Vec3 wi = clampNodeDirection(node / kClampB, node % kClampB);
        const Incident in = incident(wi);  // clamp_ is still empty: scale 1
        const Rgb albedo = directionalAlbedo(in);
        for (int c = 0; c < 3; ++c)
            scale[static_cast<size_t>(node)][c] = albedo[c] > 1 ? 1 / albedo[c] : 1.0;
        scale[static_cast<size_t>(kNodes - 1 - node)] = scale[static_cast<size_t>(node)];
    });
    // Each node keeps the smallest scale of its 3 x 3 neighbourhood: where
    // the scale changes monotonically between nodes (it falls fast towards
    // grazing), bilinear interpolation then never exceeds the scale a direction
    // needs.
    clamp_.assign(scale.size(), Rgb(1.0));
    for (int a = 0; a < kClampA; ++a)
        for (int b = 0; b < kClampB; ++b) {
            Rgb& out = clamp_[static_cast<size_t>(a) * kClampB + b];
            out = scale[static_cast<size_t>(a) * kClampB + b];
            for (int na = std::max(0, a - 1); na <= std::min(kClampA - 1, a + 1); ++na)
                for (int nb = std::max(0, b - 1); nb <= std::min(kClampB - 1, b + 1); ++nb)
                    for (int c = 0; c < 3; ++c)
                        out[c] = std::min(out[c], scale[static_cast<size_t>(na) * kClampB + nb][c]);
        }
}

Rgb DualScatteringBsdf::directionalAlbedo(const Incident& in) const {
    // theta panels over the whole range and around the specular cone (the R
    // lobe and the narrow back lobe), phi panels over the circle and around
    // the TT lobe's centre (phi_i + pi).
    const double thetaI = in.thetaI;
    std::vector<double> thetaEdges, phiEdges;
    quadrature::uniformEdges(-kHalfPi, kHalfPi, 24, &thetaEdges);
    const double halfWidth = 6 * std::max(betaR_, radians(1.0));
    quadrature::uniformEdges(std::max(-kHalfPi, -thetaI - halfWidth),
                             std::min(kHalfPi, -thetaI + halfWidth), 16, &thetaEdges);
    std::sort(thetaEdges.begin(), thetaEdges.end());
    quadrature::uniformEdges(-kPi, kPi, 12, &phiEdges);
    // Just past the surface plane (phi = +-pi/2) the light starts to cross
    // fibers: D falls from 1 to 0 within about 1 / n_f(-n) radians.
    const double transition = std::min(0.5, 1.0 / std::max(fibersPerChord_, 1.0));
    for (const double side : {-kHalfPi, kHalfPi})
        for (int k = 1; k <= 6; ++k)
            phiEdges.push_back(side + std::copysign(k * transition / 4, side));
    const Vec3 li = frame_.toLocal(in.upper);
    const double phiTT = wrapAngle(std::atan2(li.y, li.z) + kPi);
    const double gamma = radians(fiber_.params().gammaTTDeg);
    for (int k = -4; k <= 4; ++k) phiEdges.push_back(wrapAngle(phiTT + k * gamma));
    std::sort(phiEdges.begin(), phiEdges.end());
    const SphereRule rule = surfaceFiberRule(frame_, thetaEdges, phiEdges);
    Rgb albedo;
    for (size_t k = 0; k < rule.directions.size(); ++k)
        albedo += evalUpper(in, rule.directions[k]) * rule.weights[k];
    return albedo;
}

Rgb DualScatteringBsdf::albedo(const Vec3& wi) const {
    Incident in = incident(wi.z < 0 ? mirrored(wi) : wi);
    return directionalAlbedo(in) * in.scale;
}

size_t DualScatteringBsdf::memoryBytes() const {
    return sizeof(*this) + fiber_.memoryBytes() + wideLobe_.memoryBytes() +
           clamp_.size() * sizeof(Rgb) + WidthFamily::instance().memoryBytes();
}

}  // namespace weft
