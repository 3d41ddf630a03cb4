// weft/yarn/dual_scattering.h — the dual-scattering baseline (after ZMA23): an
// analytic ply BSDF from the fiber and ply parameters alone (issue 19).
//
// The paper's second baseline, [ZMA*23], aggregates fiber scattering inside a
// ply with dual-scattering theory (Zinke et al. 2008). Its text was not
// available; this is our reconstruction from Zinke's formulas specialised to
// KSZ15 fibers (docs/dual-scattering.md),
// called everywhere "dual-scattering baseline (after ZMA23)", never ZMA23 itself.
//
// Frame and conventions as the neural yarn BSDF (yarn_bsdf.h, docs/design.md 2):
// directions in the yarn frame (t, b, n) = (+x, +y, +z) at a point of the ply
// surface, eval includes the cosine of wo, wi is the camera side and wo the
// light side. For wi.z < 0 both directions are mirrored through the surface
// plane. Fiber-level terms are evaluated in the surface fiber frame, the yarn
// frame turned about n by atan(pi alpha) (yarn_lobes.h).
//
// With theta, phi the angles of wi and wo in that frame and, per channel,
//   F = F(theta_i) (the fiber's Schlick term), w_TT = the share of N_TT within
//   pi/2 of its mean (forward), and, clamping a_f <= 0.99,
//   a_f = F/2 + (1-F) C_TT w_TT,  a_b = F/2 + (1-F) C_TT (1-w_TT)   (forward, backward energy)
//   beta_f^2 = (F/2 beta_R^2 + (1-F) C_TT w_TT beta_TT^2) / a_f, beta_b^2 alike with 1-w_TT
//   A_b = a_b a_f^2 / (1-a_f^2) + a_b^3 a_f^2 / (1-a_f^2)^3                  (Zinke eq. 14-15)
//   sigma_b = (1 + d_b a_f^2)(a_b sqrt(2 bf^2 + bb^2) + a_b^3 sqrt(2 bf^2 + 3 bb^2))
//             / (a_b + a_b^3 (2 bf + 3 bb))   with bf, bb = beta_f/2, beta_b/2 (Zinke eq. 16)
// and the number of fibers the light crosses on its way to the surface point
// (the chord through the ply's cross-section towards wo, times the fibers per
// unit length of a chord):
//   n_f(wo) = (4/pi) sqrt(N rho) max(0, -n . wo_perp),   D = 1 - min(n_f, 1)
//   T_f = D + (1 - D) d_f a_f^{n_f}   (Zinke's T_f, blended to 1 where the light is direct)
// the BSDF is
//   f = D (S + d_b B(2 sigma_b)) + (T_f - D) d_f (G + pi d_b B(sqrt(4 sigma_b^2 + n_f beta_f^2)))
//   S    = the fiber's own BCSDF (fiber_bcsdf.h): single scattering
//   G    = [F g(theta_o; -theta_i, s_R) / (2 pi) + (1-F) C_TT g(theta_o; -theta_i, s_TT) w_TT / pi]
//   cos theta_o,
//          s_k^2 = beta_k^2 + n_f beta_f^2                                  (global forward
//          scattering)
//   B(s) = A_b g(theta_o; -theta_i, s) / (2 pi) cos theta_o                 (local back scattering)
// with g the longitudinal Gaussian normalised against cos^2 (longitudinal.h),
// d_f = d_b = 0.7 (Zinke's constants), and the back lobe's shift Delta_b = 0
// (KSZ15 lobes have no shifts). Zinke's formulas do not conserve energy; an
// energy clamp scales every channel's value by min(1, 1 / albedo) tabulated
// over wi (bilinear), so a lossless fiber gives albedo <= 1 (white furnace).
//
// Sampling is a fixed mixture, independent of wo: the fiber's own sampler
// (S), a wide longitudinal lobe about -theta_i with uniform azimuth (G and B),
// and the uniform sphere; pdf() is exactly its density.
#pragma once

#include <vector>

#include "weft/core/bsdf.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/fiber/fiber_params.h"
#include "weft/fiber/longitudinal.h"
#include "weft/ply/ply.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

struct DualScatteringOptions {
    double forwardScale = 0.7;  // Zinke's d_f, in [0, 1]
    double backScale = 0.7;     // Zinke's d_b, in [0, 1]
    bool energyClamp = true;    // scale to albedo <= 1 (see above)

    void validate() const;
};

class DualScatteringBsdf final : public Bsdf {
  public:
    static constexpr int kLobeSingle = 0;  // sampled by the fiber's sampler
    static constexpr int kLobeWide = 1;    // the wide longitudinal lobe
    static constexpr int kLobeUniform = 2;
    // The mixture's probabilities for those three (fixed).
    static constexpr double kPickSingle = 0.45, kPickWide = 0.45, kPickUniform = 0.10;

    // Validates the parameters (InputError) and builds the tables.
    DualScatteringBsdf(const FiberParams& fiber, const PlyParams& ply,
                       const DualScatteringOptions& options = {});

    using Bsdf::eval;
    using Bsdf::evalPdf;
    using Bsdf::pdf;
    using Bsdf::sample;
    void prepare(const Vec3& wi, BsdfIncident& in) const override;
    BsdfEval evalPdf(const BsdfIncident& in, const Vec3& wo) const override;
    BsdfSample sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const override;
    size_t memoryBytes() const override;

    // n_f(wo): fibers crossed by light arriving from wo (yarn frame, upper side).
    double fibersCrossed(const Vec3& wo) const;
    // w_TT: the share of the fiber's N_TT within pi/2 of its mean.
    double forwardShareTT() const { return forwardShareTT_; }
    // The energy clamp's scale at wi (1 without the clamp).
    Rgb clampScale(const Vec3& wi) const;
    // Directional albedo: the integral of eval(wi, .) over the sphere, by
    // quadrature (the clamp included).
    Rgb albedo(const Vec3& wi) const;
    // eval(wi, wo) in two parts, the clamp included: single scattering by the
    // surface fibers under direct light (D S), compared with a gather's R, and
    // the rest (multiple scattering: both B terms and G), compared with its M.
    struct Parts {
        Rgb single, multiple;
    };
    Parts parts(const Vec3& wi, const Vec3& wo) const;
    const SurfaceFiberFrame& frame() const { return frame_; }
    const FiberBcsdf& fiber() const { return fiber_; }

  private:
    // Per channel, what depends on theta_i alone.
    struct Channel {
        double fresnel, forward, backward;  // F, a_f, a_b
        double betaForward2;                // beta_f^2, theta_o units
        double backAmplitude, backWidth;    // A_b, 2 sigma_b (theta_o units)
    };
    struct Incident {
        bool flip;
        Vec3 upper;  // wi mirrored into the upper hemisphere
        double thetaI;
        double cos2Mu;  // cos(2 theta_i), for the lobe normalisers (mu = -theta_i)
        FiberBcsdf::Incident fiber;
        Channel channel[3];
        Rgb scale;  // the energy clamp
    };
    Incident incident(const Vec3& upperWi) const;
    // The unclamped value at (wi, wo) for the upper-hemisphere wi, and its parts.
    Parts partsUpper(const Incident& in, const Vec3& wo) const;
    Rgb evalUpper(const Incident& in, const Vec3& wo) const;
    double pdfUpper(const Incident& in, const Vec3& wo) const;
    // The integral of evalUpper(in, .) over the sphere (product Gauss-Legendre
    // panels in the surface fiber frame, refined around the R and TT lobes).
    Rgb directionalAlbedo(const Incident& in) const;
    void buildEnergyClamp();

    FiberBcsdf fiber_;
    DualScatteringOptions options_;
    SurfaceFiberFrame frame_;
    double forwardShareTT_;
    double fibersPerChord_;  // (4/pi) sqrt(N rho)
    double betaR_, betaTT_;  // radians
    LongitudinalGaussian wideLobe_;
    // min(1, 1/albedo) per channel on a grid over the upper hemisphere of wi:
    // theta (longitudinal angle in the yarn frame) x phi (azimuth about t from b).
    std::vector<Rgb> clamp_;
};

}  // namespace weft
