// weft/yarn/yarn_evaluator.h — the value of a fitted yarn model (paper 4, eq. 6-8;
// docs/design.md 7).
//
// For one ply material from a model.json:
//   P(T|wi)  the T network (3-7-7-1, sigmoid): the weight of the delta lobe
//            S_T = P(T|wi) delta(wo + wi), which the sampler draws;
//   S_R      (1 - P(T|wi)) S_f(wi~, wo~) m, paper eq. 8 in the surface fiber
//            frame with the fitted masking m (yarn_lobes.h);
//   S_M      exp(M network(wi, wo)), 6-21-21-21-3 by default, RGB;
// and, when the model has one, S_R and S_M times the fit's energy calibration
// s_R(wi), s_M(wi) (energy_calibration.h), and S_M times the energy guard
// (energy_guard.h) where the model would reflect more than it receives.
// Directions are unit vectors in the yarn shading frame of the ply hit,
// t = +x, b = +y, n = +z (docs/design.md 2), wi in the upper hemisphere (the
// yarn BSDF mirrors a lower one, yarn_bsdf.h). Values include the
// foreshortening of wo (eq. 8 and the RDM the M network learnt both do).
//
// Ablated models (the model's "ablation", paper Fig. 5; yarn_model.h): naive
// has P(T) = 0 and S_R = 0 everywhere, so S = S_M; no_r_lobe has S_R = 0.
//
// The networks are evaluated by FixedMlp (float, no heap); R in double.
// Construction validates the model once (InputError naming `source`).
#pragma once

#include <cstddef>
#include <string>

#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/yarn/energy_guard.h"
#include "weft/yarn/fixed_mlp.h"
#include "weft/yarn/packed_calibration.h"
#include "weft/yarn/yarn_incident.h"
#include "weft/yarn/yarn_lobes.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

// The parts of the model at one (wi, wo).
struct YarnComponents {
    double pT = 0;  // P(T | wi)
    Rgb r, m;       // S_R and S_M (calibration and energy guard applied), cosine included
};

class YarnEvaluator {
  public:
    // `model` is of one colour (YarnModel::forColour for a conditioned one).
    // Validates what the model reader cannot know about the renderer: network
    // shapes (3 -> 1 and 6 -> 3), output functions (sigmoid for t_net so that
    // P(T) is a probability, exp for m_net so that S_M >= 0), sizes that the
    // fixed-size evaluators hold, finite inference; the fiber and R lobe
    // parameters. `energyGuard` builds the guard's tables (energy_guard.h).
    YarnEvaluator(const YarnModel& model, const std::string& source, bool energyGuard);

    YarnAblation ablation() const { return ablation_; }
    bool hasTransmission() const { return hasTransmission_; }  // S_T is part of the model
    bool hasReflection() const { return hasReflection_; }      // S_R is part of the model
    const RLobe& rLobe() const { return rLobe_; }
    const SurfaceFiberFrame& frame() const { return rLobe_.frame(); }
    const EnergyGuard& energyGuard() const { return guard_; }

    // P(T | wi) from the T network (0 without an S_T).
    double transmission(const Vec3& wi) const;
    // The energy calibration's factors on S_R and S_M (1 without one).
    EnergyCalibration::Scales calibration(const Vec3& wi) const { return calibration_.scales(wi); }
    // S_M as the network gives it: no calibration, no guard.
    Rgb evalM(const Vec3& wi, const Vec3& wo) const;
    // out[k] = evalM(wi, wo[k]) for k < count, bit for bit, through the
    // batched network (FixedMlp::forwardBatch: 3-4 times the throughput).
    void evalMBatch(const Vec3& wi, const Vec3* wo, size_t count, Rgb* out) const;
    // The same with one wi per query: out[k] = evalM(wi[k], wo[k]).
    void evalMBatch(const Vec3* wi, const Vec3* wo, size_t count, Rgb* out) const;
    // out[k] = transmission(wi[k]) for k < count, bit for bit.
    void transmissionBatch(const Vec3* wi, size_t count, double* out) const;
    // wi's angles in the surface fiber frame.
    SurfaceFiberAngles surfaceAngles(const Vec3& wi) const;
    // wo's fiber angles in the surface fiber frame, which S_R and q_R share;
    // unset (zero) where S_R is zero (no R lobe, or wo below the surface).
    FiberBcsdf::Angles outAngles(const Vec3& wo) const;

    // Fills the model's part of `in` for in.wi: P(T) (pT, which the caller
    // has set), the R and M factors and the R lobe's fiber state.
    void prepare(const SurfaceFiberAngles& surface, YarnIncident& in) const;
    // The incident with only the model's part set (wi in the upper hemisphere).
    YarnIncident incident(const Vec3& wi) const;

    // S_R and S_M at wo for a prepared incident: the one place where the
    // model's value is put together. `out` = outAngles(wo).
    YarnComponents components(const Vec3& wo, const YarnIncident& in,
                              const FiberBcsdf::Angles& out) const;
    YarnComponents components(const Vec3& wo, const YarnIncident& in) const {
        return components(wo, in, outAngles(wo));
    }
    // out[k] = components(wo[k], in) for k < count, bit for bit, with S_M
    // through evalMBatch.
    void componentsBatch(const Vec3* wo, size_t count, const YarnIncident& in,
                         YarnComponents* out) const;
    // components() with S_M given: m = evalM(in.wi, wo), from a batch.
    YarnComponents components(const YarnIncident& in, const Vec3& wo, const FiberBcsdf::Angles& out,
                              const Rgb& m) const;

    // The energy guard's factor on S_M at wi (1 without the guard); a wi
    // below the surface counts as its mirror image.
    Rgb multipleScatteringScale(const Vec3& wi) const;

    // Bytes of the networks, the fiber's tables and the guard's tables.
    size_t memoryBytes() const;

  private:
    TransmissionMlp tNet_;
    ScatteringMlp mNet_;
    RLobe rLobe_;
    YarnAblation ablation_;
    bool hasTransmission_, hasReflection_;
    PackedCalibration calibration_;  // the model's energy calibration, in one SIMD pass
    EnergyGuard guard_;              // built last: it integrates the rest
};

}  // namespace weft
