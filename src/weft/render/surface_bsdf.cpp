#include "weft/render/surface_bsdf.h"

#include <cmath>

#include "weft/core/error.h"
#include "weft/core/json_message.h"
#include "weft/core/math.h"
#include "weft/core/sampling.h"

namespace weft::render {

namespace {

// The side of the surface wi lies on: +1 above (z >= 0), -1 below.
struct SideState {
    double side;
};

double sideOf(const Vec3& wi) { return wi.z < 0 ? -1.0 : 1.0; }

void checkColour(const Rgb& c, const std::string& what) {
    for (int k = 0; k < 3; ++k)
        if (!(c[k] >= 0 && c[k] <= 1))
            throw InputError(what + ": " + formatNumber(c[k]) +
                             " is out of range: allowed [0, 1] per channel");
}

// w mirrored to the upper hemisphere when side < 0, so that the lobes below
// are written once for z > 0.
Vec3 up(const Vec3& w, double side) { return {w.x, w.y, side * w.z}; }

}  // namespace

void TwoSidedBsdf::prepare(const Vec3& wi, BsdfIncident& in) const {
    in.emplace(wi, SideState{sideOf(wi)});
}

double TwoSidedBsdf::side(const BsdfIncident& in) { return in.get<SideState>().side; }

DiffuseBsdf::DiffuseBsdf(const Rgb& reflectance, const std::string& what)
    : reflectance_(reflectance) {
    checkColour(reflectance, what);
}

BsdfEval DiffuseBsdf::evalPdf(const BsdfIncident& in, const Vec3& wo) const {
    const double cosO = side(in) * wo.z;
    if (!(cosO > 0)) return {};
    return {reflectance_ * (kInvPi * cosO), cosineHemispherePdf(cosO)};
}

BsdfSample DiffuseBsdf::sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng&) const {
    const Vec3 wo = up(sampleCosineHemisphere(u[1], u[2]), side(in));
    return BsdfSample::fromEval(wo, evalPdf(in, wo), 0);
}

ConductorBsdf::ConductorBsdf(const Rgb& colour, double roughness, const std::string& what)
    : colour_(colour), alpha_(roughness) {
    checkColour(colour, what + ".colour");
    if (!(roughness >= kMinRoughness && roughness <= 1))
        throw InputError(what + ".roughness: " + formatNumber(roughness) +
                         " is out of range: allowed [" + formatNumber(kMinRoughness) + ", 1]");
}

double ConductorBsdf::distribution(const Vec3& h) const {
    const double cos2 = h.z * h.z;
    if (!(cos2 > 0)) return 0;
    const double tan2 = (1 - cos2) / cos2, a2 = alpha_ * alpha_;
    const double e = 1 + tan2 / a2;
    return 1 / (kPi * a2 * cos2 * cos2 * e * e);
}

double ConductorBsdf::masking(const Vec3& w) const {
    const double cos2 = w.z * w.z;
    if (!(cos2 > 0)) return 0;
    const double tan2 = (1 - cos2) / cos2;
    const double lambda = 0.5 * (std::sqrt(1 + alpha_ * alpha_ * tan2) - 1);
    return 1 / (1 + lambda);
}

BsdfEval ConductorBsdf::evalPdf(const BsdfIncident& in, const Vec3& woIn) const {
    const double sign = side(in);
    const Vec3 wi = up(in.wi(), sign), wo = up(woIn, sign);
    if (!(wi.z > 0) || !(wo.z > 0)) return {};
    const Vec3 sum = wi + wo;
    const double len = length(sum);
    if (!(len > 0)) return {};
    const Vec3 h = sum / len;
    const double d = distribution(h), woDotH = dot(wo, h);
    if (!(d > 0) || !(woDotH > 0)) return {};
    const double schlick = std::pow(1 - std::min(1.0, dot(wi, h)), 5);
    const Rgb fresnel = colour_ + (Rgb(1.0) - colour_) * schlick;
    const double g = masking(wi) * masking(wo);
    BsdfEval e;
    e.value = fresnel * (d * g / (4 * wi.z));  // f cos theta_o
    e.pdf = d * h.z / (4 * woDotH);
    return e;
}

BsdfSample ConductorBsdf::sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng&) const {
    const double sign = side(in);
    const Vec3 wi = up(in.wi(), sign);
    if (!(wi.z > 0)) return {};
    // h from D(h) cos h: tan^2 theta_h = a^2 u / (1 - u), phi uniform.
    const double tan2 = alpha_ * alpha_ * u[1] / std::max(1e-300, 1 - u[1]);
    const double cosH = 1 / std::sqrt(1 + tan2), sinH = safeSqrt(1 - cosH * cosH);
    const double phi = kTwoPi * u[2];
    const Vec3 h{sinH * std::cos(phi), sinH * std::sin(phi), cosH};
    const Vec3 wo = 2 * dot(wi, h) * h - wi;
    if (!(wo.z > 0)) return {};
    return BsdfSample::fromEval(up(wo, sign), evalPdf(in, up(wo, sign)), 0);
}

}  // namespace weft::render
