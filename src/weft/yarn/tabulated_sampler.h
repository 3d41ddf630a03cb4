// weft/yarn/tabulated_sampler.h — tabulated sampling of the yarn BSDF (the
// default): wo drawn in proportion to the model itself, so that the weight
// eval / pdf stays close to the albedo for every wi (docs/yarn.md gives the
// measured bounds).
//
//   The T lobe is picked with probability P_T = P(T) / (P(T) + E), E the
//     estimated albedo of R + M below (channel mean), so that its weight
//     P(T) / P_T matches the continuous part's (grey; paper eq. 11 uses P_T = P(T)).
//   The continuous part has density (1 - P_T) (a_R q_R + (1 - a_R) q_table):
//     q_R draws the fiber's R lobe inside S_R (its sharp, analytic part:
//       F(theta_i) g(theta_o; -theta_i, beta_R) cos theta_o / (2 pi) times
//       (1 - P(T)) m on the upper half cone) exactly, theta_o from g cos^2
//       (fiber/longitudinal.h) and phi_o uniform on the half cone, so
//       q_R = g(theta_o; -theta_i, beta_R) cos theta_o / pi and that part's
//       weight varies only with the masking m;
//     q_table follows the channel mean of the rest (S_M and the fiber's TT
//       lobe inside S_R, calibration and energy guard applied) through a
//       SamplingTable (sampling_table.h) built when the model loads (the
//       mean, not the luminance: channels whose S differ in shape all keep
//       their weights below 3 times the mean albedo);
//     a_R = E_peak / E with E_peak = (1 - P(T)) mean(s_R F(theta_i)) mbar / 2,
//       mbar the mean masking over q_R (tabulated at the table's nodes), and
//       E = E_peak + the table's energy.
// Samples report the R lobe (q_R) or the M lobe (the table); the density is
// the whole mixture, so the two are combined by one-sample MIS.
#pragma once

#include <memory>
#include <vector>

#include "weft/fiber/longitudinal.h"
#include "weft/yarn/sampling_table.h"
#include "weft/yarn/yarn_lobes.h"
#include "weft/yarn/yarn_sampler.h"

namespace weft {

class TabulatedYarnSampler final : public YarnSampler {
  public:
    // Builds the table from the model as `evaluator` gives it (guard
    // included), in parallel: about 0.08 s for a shipped model on 2 cores.
    // Keeps the evaluator: q_R is its fiber's R lobe.
    explicit TabulatedYarnSampler(std::shared_ptr<const YarnEvaluator> evaluator);

    YarnSampling kind() const override { return YarnSampling::Tabulated; }
    bool usesModelScales() const override { return true; }
    void prepare(const SurfaceFiberAngles& surface, YarnIncident& in) const override;
    bool pdfNeedsOutAngles() const override { return true; }
    double pdf(const YarnIncident& in, const Vec3& wo,
               const FiberBcsdf::Angles& out) const override;
    YarnDirectionSample sample(const YarnIncident& in, const BsdfSampleInput& u,
                               Rng& rng) const override;
    YarnLobeProbabilities lobeProbabilities(const YarnIncident& in) const override;
    size_t memoryBytes() const override;

    const SamplingTable& table() const { return table_; }

  private:
    // q_R's longitudinal lobe: the fiber's R lobe.
    const LongitudinalGaussian& peak() const;

    std::shared_ptr<const YarnEvaluator> model_;
    bool hasReflection_;
    SurfaceFiberFrame frame_;
    SamplingTable table_;
    // Per node of the table: the mean masking over q_R, the table's M term and
    // its R term per unit 1 - P(T).
    std::vector<double> peakMasking_, tableEnergyM_, tableEnergyR_;
};

}  // namespace weft
