// weft/render/surface_bsdf.h — the materials of a scene's objects: a floor,
// a backdrop, a triangle mesh (issue 43; docs/scene-format.md, "objects").
//
// Both are opaque and two-sided: in their local frame z is the surface
// normal, and they reflect into the hemisphere that wi comes from (a ray
// from either side sees the same material; nothing is transmitted). eval
// includes the foreshortening |cos theta_o| (core/bsdf.h).
//   DiffuseBsdf: Lambert, f = R / pi, sampled cosine-weighted on wi's side.
//   ConductorBsdf: a rough metal after pbrt-v4's ConductorBxDF, with
//     Trowbridge-Reitz (GGX) microfacets of roughness alpha (D(h) = 1 /
//     (pi a^2 cos^4 h (1 + tan^2 h / a^2)^2)), Smith's separable masking
//     G = G1(wi) G1(wo), and Schlick's Fresnel with F0 = the colour
//     (F = F0 + (1 - F0) (1 - |wi.h|)^5):
//       f(wi, wo) = D(h) G F / (4 |cos theta_i| |cos theta_o|),  h = (wi + wo) / |wi + wo|;
//     sampled by drawing h from D(h) |cos h| (Walter et al. 2007), wo =
//     reflect(wi, h), pdf = D(h) |cos h| / (4 |wo.h|); a wo below the surface
//     is an invalid sample.
// Parameters are validated at construction: InputError naming `what` (the
// scene field) and the range.
#pragma once

#include <string>

#include "weft/core/bsdf.h"
#include "weft/core/rgb.h"

namespace weft::render {

// What both share: prepare() records the side of the surface wi lies on
// (side(in): +1 above, -1 below), which every lobe is mirrored by.
class TwoSidedBsdf : public Bsdf {
  public:
    void prepare(const Vec3& wi, BsdfIncident& in) const final;

  protected:
    static double side(const BsdfIncident& in);
};

class DiffuseBsdf final : public TwoSidedBsdf {
  public:
    // reflectance: each channel in [0, 1].
    DiffuseBsdf(const Rgb& reflectance, const std::string& what);

    BsdfEval evalPdf(const BsdfIncident& in, const Vec3& wo) const override;
    BsdfSample sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const override;
    size_t memoryBytes() const override { return sizeof(*this); }
    using Bsdf::evalPdf;
    using Bsdf::sample;

  private:
    Rgb reflectance_;
};

class ConductorBsdf final : public TwoSidedBsdf {
  public:
    // colour (F0): each channel in [0, 1]; roughness alpha in [kMinRoughness, 1].
    static constexpr double kMinRoughness = 0.01;
    ConductorBsdf(const Rgb& colour, double roughness, const std::string& what);

    BsdfEval evalPdf(const BsdfIncident& in, const Vec3& wo) const override;
    BsdfSample sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const override;
    size_t memoryBytes() const override { return sizeof(*this); }
    using Bsdf::evalPdf;
    using Bsdf::sample;

    // The microfacet distribution D(h) and Smith's G1(w) (h, w in the local frame).
    double distribution(const Vec3& h) const;
    double masking(const Vec3& w) const;

  private:
    Rgb colour_;
    double alpha_;
};

}  // namespace weft::render
