// weft/fiber/fiber_bcsdf.h — the Khungurn et al. (2015) fiber scattering model.
//
// S_f(wi, wo) = sum_{k in R, TT} M_k(theta_i, theta_o) N_k(phi_i, phi_o)  (paper eq. 2-4)
//   M_R  = F(theta_i) g(theta_o; -theta_i, beta_R)
//   M_TT = C_TT (1 - F(theta_i)) g(theta_o; -theta_i, beta_TT)
//   N_R  = 1 / (2 pi),  N_TT = vonMises(phi_o; phi_i + pi, 1 / gamma_TT^2)
//   F(theta) = C_R + (1 - C_R)(1 - cos theta)^5  (Schlick, per channel)
// with g normalised against cos^2 on [-pi/2, pi/2] (longitudinal.h), so the
// directional albedo is exactly F + (1 - F) C_TT.
//
// Frame (docs/design.md 2, the `weft fiber` probes): the fiber tangent is +x;
// theta = asin(w.x); phi = atan2(w.z, w.y) is the azimuth in the y-z plane.
// eval() includes cos(theta_o). sample() picks R or TT in proportion to their
// albedo summed over the channels weighted by the incident's importance
// (BsdfIncident::importance, 1 by default: the channel average), then samples
// theta_o exactly from g cos^2 and phi_o
// uniformly (R) or from the von Mises lobe (TT); pdf() is that mixture's
// density in solid angle (the (theta, phi) density divided by cos theta_o).
//
// Why the importance: a channel whose R / TT split differs from the average's
// gets weights eval_c / pdf away from its albedo (cotton's blue up to 2.1, E[w^2]
// 1.07 per event), and a path's throughput is their product. In near-white
// fibers a path in cloth makes hundreds of events, so that product is
// heavy-tailed (Table 2's cotton weave in fiber mode at max_depth 1000: c =
// relMSE x spp 116 at 64 spp, 5830 at 1024). With the lobe picked by the
// throughput-weighted albedos, sum_c T_c w_c = sum_c T_c a_c for every sample
// (a_c the albedo): the weighted sum of the path's throughput is never larger
// than before the event, so no channel can grow without bound.
#pragma once

#include "weft/core/bsdf.h"
#include "weft/fiber/fiber_params.h"
#include "weft/fiber/longitudinal.h"
#include "weft/fiber/von_mises.h"

namespace weft {

class FiberBcsdf final : public Bsdf {
  public:
    static constexpr int kLobeR = 0;
    static constexpr int kLobeTT = 1;

    // Validates the parameters (InputError) and tabulates the normalisers.
    explicit FiberBcsdf(const FiberParams& params);

    const FiberParams& params() const { return params_; }

    // The Bsdf interface (core/bsdf.h); the incident state is wi's angles,
    // F(theta_i) and the probability of the R lobe.
    using Bsdf::eval;
    using Bsdf::evalPdf;
    using Bsdf::pdf;
    using Bsdf::sample;
    void prepare(const Vec3& wi, BsdfIncident& in) const override;
    BsdfEval evalPdf(const BsdfIncident& in, const Vec3& wo) const override;
    Rgb eval(const BsdfIncident& in, const Vec3& wo) const override;
    double pdf(const BsdfIncident& in, const Vec3& wo) const override;
    BsdfSample sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const override;

    size_t memoryBytes() const override;

    // Analytic directional albedo F(theta_i) + (1 - F(theta_i)) C_TT.
    Rgb albedo(const Vec3& wi) const;
    // Schlick term F(theta) per channel (paper eq. 4).
    Rgb fresnel(double cosTheta) const;
    // The R lobe's longitudinal Gaussian g(theta; mu, beta_R) (the yarn's q_R draws from it).
    const LongitudinalGaussian& longitudinalR() const { return gR_; }

    // Longitudinal angle of a direction and its projection on the normal
    // plane (y, z); azimuth differences come from dot products of the
    // projections, so no atan2 for phi is needed.
    struct Angles {
        double sinTheta, cosTheta, theta;
        double y, z;
    };
    static Angles anglesOf(const Vec3& w);
    // What prepare() stores: all that depends on wi alone. Public for models
    // that embed the fiber lobe (the yarn's R lobe) and keep it in their own
    // incident state: evalPrepared(incident(wi), anglesOf(wo)) == eval(wi, wo).
    struct Incident {
        Angles angles;
        Rgb fresnel;          // F(theta_i)
        double probabilityR;  // of picking the R lobe
    };
    Incident incident(const Vec3& wi, const Rgb& importance = Rgb(1.0)) const;
    // The same from anglesOf(wi), for a caller that has them.
    Incident incident(const Angles& wi, const Rgb& importance = Rgb(1.0)) const;
    Rgb evalPrepared(const Incident& in, const Angles& out) const;
    BsdfEval evalPdfPrepared(const Incident& in, const Angles& out) const;

  private:
    // Probability of picking the R lobe for this incident angle and channel importance.
    double probabilityR(const Rgb& f, const Rgb& importance) const;
    void evalAndPdf(const Incident& in, const Angles& out, Rgb* value, double* density) const;

    FiberParams params_;
    LongitudinalGaussian gR_, gTT_;
    VonMises nTT_;
};

}  // namespace weft
