#include "weft/render/sphere_light.h"

#include <algorithm>
#include <cmath>

#include "weft/core/error.h"
#include "weft/core/json_message.h"
#include "weft/core/math.h"
#include "weft/render/scene_reader.h"

namespace weft::render {

// ---------------------------------------------------------------------------
// SphereLight

SphereLight::SphereLight(const Vec3& center, double radius, const Rgb& radiance)
    : center_(center), radius_(radius), radiance_(radiance) {
    if (!isFinite(center))
        throw InputError("sphere light: center " + streamedText(center) + " must be finite");
    if (!(std::isfinite(radius) && radius > 0))
        throw InputError("sphere light: radius = " + streamedText(radius) +
                         " must be finite and > 0");
    checkLightRadiance(radiance, "sphere light");
}

LightSample SphereLight::sample(const Vec3& p, const std::array<double, 2>& u) const {
    const Vec3 toCenter = center_ - p;
    const double dc2 = dot(toCenter, toCenter), r2 = radius_ * radius_;
    if (!(dc2 > r2)) return {};  // inside or on the sphere (or p is NaN)
    const double dc = std::sqrt(dc2);
    // pbrt-v3 Sphere::Sample(ref, u): uniform in the cone of half-angle
    // theta_max, sin^2 theta_max = r^2 / dc^2. 1 - cos theta is sampled
    // directly to keep the precision of small, distant spheres.
    const double sin2Max = r2 / dc2;
    const double oneMinusCosMax = sin2Max / (1.0 + safeSqrt(1.0 - sin2Max));
    const double t = std::clamp(u[0], 0.0, 1.0) * oneMinusCosMax;
    const double cosTheta = 1.0 - t, sinTheta = safeSqrt(t * (2.0 - t));
    const double phi = kTwoPi * u[1];
    const Frame frame = Frame::fromZ(toCenter / dc);
    LightSample s;
    s.wi = frame.fromLocal({sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta});
    // Nearer root of |p + t wi - c|^2 = r^2 in the cancellation-free form
    // (dc^2 - r^2) / (b + sqrt(disc)), b = dc cos theta.
    const double b = dc * cosTheta;
    s.distance = (dc - radius_) * (dc + radius_) / (b + safeSqrt(r2 - dc2 * t * (2.0 - t)));
    s.radiance = radiance_;
    s.pdf = 1.0 / (kTwoPi * oneMinusCosMax);
    return s;
}

double SphereLight::pdf(const Vec3& p, const Vec3& wi) const {
    const Vec3 toCenter = center_ - p;
    const double dc2 = dot(toCenter, toCenter), r2 = radius_ * radius_;
    if (!(dc2 > r2)) return 0;
    // wi is in the cone iff the ray p + t wi (t > 0) meets the sphere: the
    // same test as intersect()'s discriminant.
    const double b = dot(toCenter, wi);
    if (!(b > 0)) return 0;
    const Vec3 perp = toCenter - wi * b;
    if (dot(perp, perp) > r2) return 0;
    const double sin2Max = r2 / dc2;
    return 1.0 / (kTwoPi * sin2Max / (1.0 + safeSqrt(1.0 - sin2Max)));
}

Rgb SphereLight::radiance(const Vec3&) const { return radiance_; }

double SphereLight::intersect(const Vec3& org, const Vec3& dir, double tMax) const {
    // Roots of t^2 + 2 hb t + c = 0 computed without cancellation (Haines et
    // al., "Precision Improvements for Ray/Sphere Intersection", Ray Tracing
    // Gems ch. 7): the discriminant from the closest-approach vector.
    const Vec3 f = org - center_;
    const double hb = dot(f, dir);
    const Vec3 closest = f - dir * hb;
    const double r2 = radius_ * radius_;
    const double disc = r2 - dot(closest, closest);
    if (!(disc >= 0)) return -1.0;
    const double c = dot(f, f) - r2;
    const double q = -(hb + std::copysign(std::sqrt(disc), hb));
    if (q == 0) return -1.0;  // grazing at the origin
    const double t0 = std::min(q, c / q), t1 = std::max(q, c / q);
    const double tMin = kIntersectEpsilon * (std::sqrt(dot(f, f)) + radius_);
    if (t0 > tMin && t0 < tMax) return t0;
    if (t1 > tMin && t1 < tMax) return t1;
    return -1.0;
}

// ---------------------------------------------------------------------------
// The scene type

nlohmann::json SphereLightDesc::params() const {
    return {{"center", vecJson(center)}, {"radius", radius}, {"radiance", rgbJson(radiance)}};
}

std::unique_ptr<Light> SphereLightDesc::create() const {
    return std::make_unique<SphereLight>(center, radius, radiance);
}

LightType sphereLightType() {
    return {"sphere", [](JsonObjectReader& r, const std::string&) {
                r.allowKeys({"type", "center", "radius", "radiance"});
                const Vec3 center = readSceneVec3(r, "center");
                const double radius = r.number("radius", sceneLengthRange());
                return std::shared_ptr<const LightDesc>(
                    std::make_shared<SphereLightDesc>(center, radius, readRadiance(r, "radiance")));
            }};
}

Rgb SphereLight::power(double) const { return radiance_ * (kPi * 4.0 * kPi * radius_ * radius_); }

}  // namespace weft::render
