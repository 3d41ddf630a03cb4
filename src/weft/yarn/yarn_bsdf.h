// weft/yarn/yarn_bsdf.h — the aggregated yarn BSDF (paper 4, eq. 6-11; docs/design.md 7).
//
// S(wi, wo) = S_T + S_R + S_M for one ply material, from a fitted model.json:
//   S_T = P(T|wi) delta(wo + wi)           T network (3-7-7-1, sigmoid)
//   S_R = (1 - P(T|wi)) S_f(wi~, wo~) m     paper eq. 8 in the surface fiber frame,
//                                          with the fitted masking m (yarn_lobes.h)
//   S_M = exp(M network(wi, wo))            6-21-21-21-3 by default, RGB
// and, when the model has one, S_R and S_M times the fit's energy calibration
// s_R(wi), s_M(wi) (energy_calibration.h).
// Directions are unit vectors in the yarn shading frame of the ply hit:
// t = +x (ply tangent), b = +y, n = +z (outward normal), docs/design.md 2; the
// caller converts world directions with Frame(t, b, n). The BSDF contract is
// core/bsdf.h: eval includes the foreshortening of wo (eq. 8 and the RDM the
// M network learnt both do).
//
//   eval(wi, wo)  the continuous part R + M (the delta T is never returned).
//   pdf(wi, wo)   density of sample() over the continuous part, per unit solid
//                 angle: p_R pdf_R + p_M pdf_M (paper eq. 10, 11) with
//                 p_T = P(T|wi), p_R = (1 - p_T) kappa_R, p_M = (1 - p_T)(1 - kappa_R).
//                 It integrates to 1 - p_T over the sphere (the rest is the delta).
//   sample(wi, u) picks T, R or M with p_T, p_R, p_M by u[0]:
//                 T: wo = -wi exactly, weight = P(T|wi) / p_T = 1 (grey),
//                    pdf = 0, isDelta = true, lobe kLobeT;
//                 R, M: wo from the lobe's sampler (paper 4.4, u[1], u[2]), then
//                    weight = eval / pdf with both from the one routine that
//                    eval() and pdf() use, so the two lobes are combined by
//                    one-sample MIS (the balance heuristic over the mixture).
// Incident directions below the surface (wi.z < 0): the networks were trained
// on the upper hemisphere only and a ply is never lit from inside, so the BSDF
// is made two-sided the way Mitsuba's `twosided` adapter does it: wi and wo are
// both mirrored through the surface plane (z -> -z) and the upper-hemisphere
// BSDF is used. eval, pdf and sample all do this, so they stay consistent;
// wi.z == 0 counts as upper.
//
// Energy guard (on by default, YarnBsdfOptions): a fitted M network can
// overshoot, so that P(T|wi) + E_R(wi) + E_M(wi) > 1 for some wi (E: the
// integral over wo; measured on real fits, mostly near grazing incidence and
// for nearly lossless channels such as gabardine's red). In a path tracer
// such a BSDF adds energy at every bounce. Since R <= (1 - P(T)) times the
// fiber albedo, P(T) + E_R <= 1 without an energy calibration, so the guard
// scales S_M, per channel, by s(wi) = min(1, (1 - P(T|wi) - E_R(wi)) / E_M(wi));
// should a calibration push E_R above 1 - P(T), R is scaled down to it and M to 0. P(T|wi) and
// the fiber albedo a_f = F + (1 - F) C_TT at wi (in the surface fiber frame),
// which carry the sharp features, are exact at eval time; two tables,
// computed at construction by Gauss-Legendre quadrature (in parallel) and
// interpolated (bilinearly; cubic across the rows of E_M), give the rest:
//   E_M on a 24 x 48 grid of the yarn frame's polar angle (crowded towards
//       grazing incidence, where M changes fastest: 90 (1 - (1 - a/23)^2)
//       degrees; cubic across rows) and azimuth (every 7.5 degrees);
//   E_R / ((1 - P(T)) a_f), the part of eq. 8 left by masking and the half
//       cone, on a 24 x 24 grid of the surface-fiber longitudinal angle and
//       azimuth from n (uniform in [-90, 90] degrees), where it is smooth.
// At the nodes the guarded albedo is 1 up to the quadrature error; between
// them it is as good as the interpolation (docs/yarn.md gives measured
// values). Only cells of the M table next to a node whose albedo exceeds 0.98
// are guarded; elsewhere s = 1 after one table lookup, and when there is no
// such node the guard is off altogether. Where the model conserves energy
// s = 1 and eval is the model's own value.
// `weft yarn check` reports the raw model's albedo against the RDM, since
// that is what the fit must get right.
//
// Ablated models (the model's "ablation", paper Fig. 5; yarn/yarn_model.h):
// naive has P(T) = 0 and S_R = 0 everywhere (eval, pdf, sample,
// transmission()), so S = S_M; no_r_lobe has S_R = 0, so S = S_T + S_M. For
// both, the lobe selection uses kappa_R = 0 whatever the file says, so R is
// never sampled, and the energy guard runs with E_R = 0.
//
// Sampling (YarnBsdfOptions::sampling). Tabulated (the default) draws wo in
// proportion to the model itself, so that the weight eval / pdf stays close
// to the albedo for every wi (docs/yarn.md gives the measured bounds):
//   the T lobe is picked with probability P_T = P(T) / (P(T) + E), E the
//     estimated albedo of R + M below (channel mean), so that its weight P(T) / P_T
//     matches the continuous part's (grey; paper eq. 11 uses P_T = P(T));
//   the continuous part, density (1 - P_T) (a_R q_R + (1 - a_R) q_table):
//     q_R draws the fiber's R lobe inside S_R (its sharp, analytic part:
//       F(theta_i) g(theta_o; -theta_i, beta_R) cos theta_o / (2 pi) times
//       (1 - P(T)) m on the upper half cone) exactly, theta_o from g cos^2
//       (fiber/longitudinal.h) and phi_o uniform on the half cone, so
//       q_R = g(theta_o; -theta_i, beta_R) cos theta_o / pi and that part's
//       weight varies only with the masking m;
//     q_table follows the channel mean of the rest (S_M and the fiber's TT lobe
//       inside S_R, calibration and energy guard applied) through a
//       SamplingTable (sampling_table.h) built when the model loads (the
//       mean, not the luminance: channels whose S differ in shape all keep
//       their weights below 3 times the mean albedo);
//     a_R = E_peak / E with E_peak = (1 - P(T)) mean(s_R F(theta_i)) mbar / 2,
//       mbar the mean masking over q_R (tabulated at the table's nodes), and
//       E = E_peak + the table's energy.
//   Samples report kLobeR (q_R) or kLobeM (the table); the density is the
//   whole mixture, so the two are combined by one-sample MIS.
// The pdf integrates to 1 - P_T. Fitted is the paper's scheme (eq. 10-11,
// above). Cosine, for the ablation "cosine sampling" of paper Fig. 5, keeps the delta T lobe
// (chosen with p_T = P(T|wi) as above, same weight) but draws the continuous
// part from a cosine density about n on either side of the surface, each with
// probability 1/2 (the yarn BSDF covers the whole sphere: M also transmits):
//   pdf(wi, wo) = (1 - p_T) |wo.z| / (2 pi),
// which integrates to 1 - p_T over the sphere. u[0] picks T, then (rescaled)
// the side; u[1], u[2] the direction. Such samples report lobe kLobeM (the
// continuous part); eval is unchanged and weight = eval / pdf as always.
//
// The networks are evaluated by FixedMlp (float, no heap); R and the pdfs in
// double. Construction validates the model once (InputError naming `source`).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "weft/core/bsdf.h"
#include "weft/core/rng.h"
#include "weft/fiber/longitudinal.h"
#include "weft/yarn/packed_calibration.h"
#include "weft/yarn/sampling_table.h"
#include "weft/yarn/yarn_lobes.h"
#include "weft/yarn/yarn_model.h"
#include "weft/yarn/fixed_mlp.h"

namespace weft {

// How sample() draws the continuous part (above).
enum class YarnSampling { Tabulated, Fitted, Cosine };
// "tabulated", "fitted" or "cosine"; InputError naming `what` and the allowed values otherwise.
YarnSampling parseYarnSampling(const std::string& name, const std::string& what);
const char* yarnSamplingName(YarnSampling sampling);

struct YarnBsdfOptions {
    bool energyGuard = true;  // scale S_M where the model's albedo exceeds 1 (above)
    YarnSampling sampling = YarnSampling::Tabulated;
};

class YarnBsdf final : public Bsdf {
  public:
    static constexpr int kLobeT = 0;
    static constexpr int kLobeR = 1;
    static constexpr int kLobeM = 2;

    // Validates what the model reader cannot know about the renderer: network
    // shapes (3 -> 1 and 6 -> 3), output functions (sigmoid for t_net so that
    // P(T) is a probability, exp for m_net so that S_M >= 0) and sizes that the
    // fixed-size evaluator holds; the fiber, R lobe and sampling parameters.
    // A colour-conditioned model (yarn_model.h) is rendered at its own
    // gathered colour, model.forColour(model.fiber.cTT); pass
    // model.forColour(cTT) for another colour.
    explicit YarnBsdf(const YarnModel& model, const std::string& source = "yarn model",
                      const YarnBsdfOptions& options = {});
    // loadYarnModel(path), then the constructor with the path as source.
    static YarnBsdf load(const std::string& path, const YarnBsdfOptions& options = {});

    // The Bsdf interface (core/bsdf.h); the incident state is what depends
    // on wi alone (P(T), the calibration, the energy guard), so a slice
    // (Bsdf::slice) pays for it once; pdf(wi, wo) computes P(T) alone.
    // sample(wi, u) draws the von Mises rejection steps from
    // bsdfSampleRng(u), as FiberBcsdf does.
    using Bsdf::eval;
    using Bsdf::evalPdf;
    using Bsdf::pdf;
    using Bsdf::sample;
    void prepare(const Vec3& wi, BsdfIncident& in) const override;
    BsdfEval evalPdf(const BsdfIncident& in, const Vec3& wo) const override;
    Rgb eval(const BsdfIncident& in, const Vec3& wo) const override;
    double pdf(const BsdfIncident& in, const Vec3& wo) const override;
    double pdf(const Vec3& wi, const Vec3& wo) const override;
    BsdfSample sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const override;

    // The networks, the energy guard's and the sampling tables.
    size_t memoryBytes() const override;

    // P(T | wi) from the T network (0 for a naive model).
    double transmission(const Vec3& wi) const;

    YarnAblation ablation() const { return ablation_; }
    YarnSampling sampling() const { return sampling_; }

  private:
    // The constructor proper, for a model of one colour.
    struct OneColour {};
    YarnBsdf(const YarnModel& model, const std::string& source, const YarnBsdfOptions& options,
             OneColour);

    // What eval and pdf need of wi (in the upper hemisphere): P(T), the
    // calibration of R, and the calibration times the energy guard of M.
    struct Incident {
        double pT = 0;
        Rgb rScale, mScale;
        // Tabulated sampling: the probability of the T lobe and, given the
        // continuous part, of q_R; theta_i in the surface fiber frame; the table's rows and nodes.
        double pickT = 0, pickR = 0, thetaI = 0;
        SamplingTable::Incident table;
        FiberBcsdf::Incident fiber{};  // the R lobe's fiber state (surface fiber frame)
    };
    // What prepare() stores in a BsdfIncident (which holds wi as given).
    struct Prepared {
        bool flip;   // wi.z < 0: wi and wo are mirrored
        Vec3 upper;  // wi mirrored into the upper hemisphere
        Incident in;
    };

  public:
    // The parts of eval for one pair, and the lobe probabilities of sample().
    struct Components {
        double pT = 0;  // P(T | wi)
        Rgb r, m;       // S_R and S_M (calibration and energy guard applied), cosine included
    };
    // p_T, p_R, p_M of sample(); with cosine sampling p_R = 0 and p_M is the
    // whole continuous part; with tabulated sampling p_R is the share of q_R
    // and p_M the table's.
    Components components(const Vec3& wi, const Vec3& wo) const;
    struct LobeProbabilities {
        double t = 0, r = 0, m = 0;
    };
    LobeProbabilities lobeProbabilities(const Vec3& wi) const;

    // S_M alone (the network, no energy guard), in the upper-hemisphere convention (no mirroring).
    Rgb evalM(const Vec3& wi, const Vec3& wo) const;
    // The energy guard's factor on S_M for this wi (1 without the guard).
    Rgb multipleScatteringScale(const Vec3& wi) const;
    // Whether the guard scales S_M anywhere (false: eval is exactly the model).
    bool energyGuardActive() const { return guardActive_; }

    const RLobe& rLobe() const { return rLobe_; }
    const SamplingLobes& samplingLobes() const { return lobes_; }
    const SurfaceFiberFrame& surfaceFiberFrame() const { return lobes_.frame(); }
    // The tabulated sampler's table (empty unless the sampling is Tabulated).
    const SamplingTable& samplingTable() const { return table_; }

    // The energy guard's tables (above). M table node (a, b), a < kGuardTheta,
    // b < kGuardPhi: yarn-frame polar angle guardPolarAngle(a), azimuth
    // -pi + 2 pi b / kGuardPhi. R table node (a, b), both < kGuardFiber:
    // surface-fiber angles guardFiberAngle(a), guardFiberAngle(b), i.e. the
    // local direction (sin theta~, cos theta~ sin phi~, cos theta~ cos phi~).
    static constexpr int kGuardTheta = 24;
    static constexpr int kGuardPhi = 48;
    static constexpr int kGuardFiber = 24;
    static constexpr double kGuardThreshold = 0.98;
    static double guardPolarAngle(int index);  // pi/2 (1 - (1 - index / 23)^2)
    static double guardFiberAngle(int index);  // -pi/2 + pi index / 23

  private:
    // wi in the surface fiber frame: the R lobe's fiber angles and the
    // azimuth from n, phi = atan2(y, max(z, 0)), which the guard's R table and
    // the sampling table share (one atan2 each for theta and phi per wi).
    struct SurfaceIncident {
        Vec3 local;
        FiberBcsdf::Angles angles;
        double phi = 0;
    };
    SurfaceIncident surfaceIncident(const Vec3& wi) const;
    Incident incident(const Vec3& wi, double pT) const;
    // S_R and S_M (calibration and guard applied) for wi in the upper
    // hemisphere: the one place where the model's value is put together.
    Components componentsUpper(const Vec3& wi, const Vec3& wo, const Incident& in) const;
    // The same with wo's angles in the surface fiber frame (outAngles), which
    // S_R and q_R share.
    Components componentsUpper(const Vec3& wi, const Vec3& wo, const Incident& in,
                               const FiberBcsdf::Angles& out) const;
    FiberBcsdf::Angles outAngles(const Vec3& wo) const;
    // eval and pdf for wi in the upper hemisphere: the one place where both are computed.
    void evalAndPdf(const Vec3& wi, const Vec3& wo, const Incident& in, Rgb* value,
                    double* density) const;
    double transmissionUpper(const Vec3& wi) const;
    struct GuardScales {
        Rgb r{1.0}, m{1.0};
    };
    GuardScales scaleUpper(const Vec3& wi, const SurfaceIncident& surface, double pT,
                           const EnergyCalibration::Scales& calibration) const;
    void buildEnergyGuard();
    void buildSamplingTable();
    const LongitudinalGaussian& peakLongitudinal() const { return rLobe_.fiber().longitudinalR(); }
    // The fiber's R lobe inside S_R (tabulated sampling, above), calibration applied.
    Rgb reflectionPeak(const Vec3& wi, const Vec3& wo, const Incident& in) const;
    // Density of the continuous part of sample() (1 - P_T included).
    double continuousPdf(const Vec3& wo, const FiberBcsdf::Angles& out, const Incident& in) const;

    TransmissionMlp tNet_;
    ScatteringMlp mNet_;
    RLobe rLobe_;
    SamplingLobes lobes_;
    YarnAblation ablation_;
    bool hasTransmission_, hasReflection_;  // S_T and S_R are part of the BSDF
    YarnSampling sampling_;
    double kappaR_;  // 0 without an R lobe
    PackedCalibration calibration_;  // the model's energy calibration, in one SIMD pass
    bool guardActive_ = false;
    // Tables per channel: E_R / ((1 - P(T)) a_f) before the calibration (whose
    // scale is exact at eval time), kGuardFiber x kGuardFiber
    // (fiber angles), and E_M, kGuardTheta x kGuardPhi (yarn angles).
    std::vector<Rgb> guardReflectance_, guardEnergyM_;
    // 1 where a cell of the M table (rows a, a + 1; columns b, b + 1) may need the guard.
    std::vector<uint8_t> guardCell_;
    // Tabulated sampling: the table and the mean masking over q_R at the
    // table's nodes; q_R's longitudinal lobe is the fiber's (peakLongitudinal).
    SamplingTable table_;
    std::vector<double> peakMasking_, tableEnergyM_, tableEnergyR_;
    // Lookups in the two tables.
    struct GuardCell {
        int a0 = 0, b0 = 0, b1 = 0;
        double fa = 0, fb = 0;
    };
    GuardCell guardCell(const Vec3& wi) const;
    Rgb keptReflectance(const SurfaceIncident& surface) const;
    Rgb energyM(const GuardCell& cell) const;
};

}  // namespace weft
