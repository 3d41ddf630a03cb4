// weft/yarn/yarn_lobes.h — the analytic parts of the yarn model: the R lobe
// (paper eq. 8) and the sampling densities (paper eq. 9-10).
//
// Directions are local to the yarn frame (t, b, n) = (+x, +y, +z), as in the
// RDM (docs/design.md 2). The surface fiber frame turns t about n by the surface
// tilt phi~ = atan(pi alpha): in yarn-local coordinates the frame is turned
// about n, t~ = cos(phi~) t + sin(phi~) b and b~ = -sin(phi~) t + cos(phi~) b,
// so (t~, b~, n) has the same handedness as (t, b, n). In that frame the fiber model's own convention applies (fiber
// tangent +x, azimuth in the y-z plane): theta = asin(w.t~), and the
// azimuth phi = atan2(w.b~, w.n) is measured from n, so |phi| < pi/2 is the
// upper half of the cone (paper 4.4).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/fiber/von_mises.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

// A yarn-frame direction mirrored through the surface plane (z -> -z): the
// yarn BSDFs evaluate a lower-hemisphere wi as its mirror image.
constexpr Vec3 mirrored(const Vec3& w) { return {w.x, w.y, -w.z}; }

struct SurfaceFiberFrame {
    double cosTilt = 1, sinTilt = 0;

    static SurfaceFiberFrame fromTiltDeg(double tiltDeg);
    // Tilt of the surface fibers of a ply with twist alpha: atan(pi alpha), degrees.
    static double tiltDegOfTwist(double twist);

    // Yarn-local (t, b, n) coordinates -> surface-fiber-local (t~, b~, n).
    Vec3 toLocal(const Vec3& w) const {
        return {cosTilt * w.x + sinTilt * w.y, -sinTilt * w.x + cosTilt * w.y, w.z};
    }
    Vec3 fromLocal(const Vec3& w) const {
        return {cosTilt * w.x - sinTilt * w.y, sinTilt * w.x + cosTilt * w.y, w.z};
    }

    // Surface-fiber-local direction of longitudinal angle theta and azimuth
    // phi from n: (sin theta, cos theta sin phi, cos theta cos phi).
    static Vec3 localDirection(double theta, double phi) {
        const double cosTheta = std::cos(theta);
        return {std::sin(theta), cosTheta * std::sin(phi), cosTheta * std::cos(phi)};
    }
    // The same as a yarn-local direction.
    Vec3 direction(double theta, double phi) const { return fromLocal(localDirection(theta, phi)); }

    // The angles of a yarn-local direction: theta = asin(w~.x), its cosine,
    // and the cosine of the azimuth from n in the (b~, n) plane (1 on the
    // fiber axis, where the azimuth is undefined).
    struct Angles {
        double theta, cosTheta, cosPhi;
    };
    Angles angles(const Vec3& w) const {
        const Vec3 local = toLocal(w);
        const double sinTheta = std::clamp(local.x, -1.0, 1.0);
        const double cosTheta = std::sqrt(std::max(0.0, 1.0 - sinTheta * sinTheta));
        const double cosPhi = cosTheta > 0 ? std::clamp(local.z / cosTheta, -1.0, 1.0) : 1.0;
        return {std::asin(sinTheta), cosTheta, cosPhi};
    }
    // Its longitudinal angle alone.
    double longitudinalAngle(const Vec3& w) const {
        return std::asin(std::clamp(toLocal(w).x, -1.0, 1.0));
    }
};

// Masking term of the R lobe, form "symmetric-quadratic" (docs/model-format.md):
//     m(wi, wo) = clamp(c0 + c1 (mu_i + mu_o) + c2 mu_i mu_o + c3 (mu_i^2 + mu_o^2), 0, 1),
// mu = w.n. Symmetric in wi and wo, so the R lobe stays reciprocal.
inline constexpr int kMaskingCoefficients = 4;
std::array<double, kMaskingCoefficients> maskingBasis(double muI, double muO);

// S_R(wi, wo) = (1 - P(T|wi)) S_f(wi~, wo~) [m(wi, wo)] for wi.n > 0 and wo.n > 0, else 0.
class RLobe {
public:
    RLobe(const FiberParams& fiber, const RLobeParams& params);

    const RLobeParams& params() const { return params_; }
    const SurfaceFiberFrame& frame() const { return frame_; }
    const FiberBcsdf& fiber() const { return fiber_; }

    // The masking factor m (1 without a masking term).
    double masking(const Vec3& wi, const Vec3& wo) const;
    // Plain eq. 8 without (1 - P(T|wi)) and without masking: S_f in the surface fiber frame.
    Rgb evalFiber(const Vec3& wi, const Vec3& wo) const;
    // The full lobe for a given P(T|wi).
    Rgb eval(const Vec3& wi, const Vec3& wo, double pT) const;
    // The same with what depends on wi, and wo's angles, computed once (the
    // yarn BSDF's incident state): fiberIn = fiber().incident(frame().toLocal(wi)),
    // out = FiberBcsdf::anglesOf(frame().toLocal(wo)).
    Rgb eval(const Vec3& wi, const Vec3& wo, const FiberBcsdf::Incident& fiberIn,
             const FiberBcsdf::Angles& out, double pT) const;

private:
    RLobeParams params_;
    SurfaceFiberFrame frame_;
    FiberBcsdf fiber_;
};

// Gaussian in theta truncated to [-pi/2, pi/2] and normalised there: the
// longitudinal density of the sampling lobes (paper eq. 10's g). Sampling by
// the inverse CDF (erf / erfInv).
class TruncatedGaussian {
public:
    explicit TruncatedGaussian(double beta);  // standard deviation, radians, > 0
    double beta() const { return beta_; }
    double pdf(double theta, double mu) const;
    double sample(double mu, double u) const;
    // 1 / (mass of the untruncated Gaussian inside [-pi/2, pi/2]); pdf() with it
    // precomputed, for loops over many theta at one mu.
    double inverseMass(double mu) const;
    double pdf(double theta, double mu, double inverseMass) const;

private:
    double beta_;
};

// The continuous sampling densities of paper eq. 10 in solid angle, for
// yarn-local wi, wo (wi in the upper hemisphere):
//   pdf_R = g(theta_o; -theta_i, beta_R) / (pi cos theta_o) on the upper half cone |phi_o| < pi/2,
//   pdf_M = kappa_M g(theta_o; -theta_i, beta_M) vM(phi_o; 0, 1/gamma_M^2) / cos theta_o
//           + (1 - kappa_M) / (4 pi),
// angles in the surface fiber frame. Lobe choice (eq. 11) is the BSDF's business.
class SamplingLobes {
public:
    SamplingLobes(const FiberParams& fiber, double tiltDeg, const SamplingParams& params);

    const SamplingParams& params() const { return params_; }
    double pdfR(const Vec3& wi, const Vec3& wo) const;
    double pdfM(const Vec3& wi, const Vec3& wo) const;

    // The same pdf_M from precomputed angles (fitting loops): a direction's
    // longitudinal angle, its cosine and the cosine of its azimuth from n, all
    // in the surface fiber frame; `inverseMass` = longitudinalM().inverseMass(-thetaI).
    using Angles = SurfaceFiberFrame::Angles;
    Angles anglesOf(const Vec3& w) const { return frame_.angles(w); }
    const TruncatedGaussian& longitudinalM() const { return gM_; }
    double pdfM(double thetaI, double inverseMass, const Angles& out, double vonMisesDensity) const;
    double vonMisesM(double cosPhi) const { return vonMisesM_.pdfOfCos(cosPhi); }
    const SurfaceFiberFrame& frame() const { return frame_; }

    // Sampling (paper 4.4) with exactly the densities above. In the surface
    // fiber frame a direction of longitudinal angle theta and azimuth phi
    // (from n) is (sin theta, cos theta sin phi, cos theta cos phi).
    // R: theta_o = g(.; -theta_i, beta_R) by its inverse CDF (u1), phi_o
    // uniform in [-pi/2, pi/2) (u2).
    Vec3 sampleR(const Vec3& wi, double u1, double u2) const;
    // M: the cone lobe when uLobe < kappa_M (theta_o from g(.; -theta_i,
    // beta_M) by u1, phi_o von Mises about 0: u2 drives the first proposal,
    // rng the rejection steps), otherwise the uniform sphere (u1, u2).
    Vec3 sampleM(const Vec3& wi, double uLobe, double u1, double u2, Rng& rng) const;

private:
    SamplingParams params_;
    SurfaceFiberFrame frame_;
    TruncatedGaussian gR_, gM_;
    VonMises vonMisesM_;
};

}  // namespace weft
