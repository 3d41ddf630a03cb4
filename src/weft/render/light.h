// weft/render/light.h — the light interface of the path tracer, and the
// registry of light types the scene file describes (docs/scene-format.md).
//
// Every light is behind one interface, so that the path tracer does
// next-event estimation (sample) and multiple importance sampling (pdf) the
// same way for each. Directions are world-space unit vectors;
// LightSample::wi points from the shading point towards the light.
//
// A light type is registered once (light_types.cpp) with its name, the
// reader of its JSON object and, through the LightDesc it reads, its writer,
// the files it depends on (for the scene's inputs and hash) and its factory:
// a new light type is one file (its Light, its LightDesc and its LightType)
// and one line in light_types.cpp. The types: constant (constant_light.h),
// envmap and sky (environment_light.h), sphere (sphere_light.h), point and
// directional (delta_lights.h).
#pragma once

#include <array>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>
#include <vector>

#include "weft/core/json_reader.h"
#include "weft/core/rgb.h"
#include "weft/core/vec.h"

namespace weft::render {

struct LightSample {
    Vec3 wi;              // unit direction from the shading point to the light
    Rgb radiance;         // emitted radiance arriving along -wi (not divided by pdf)
    double pdf = 0;       // solid-angle density of wi at the shading point; 0: no sample
    double distance = 0;  // to the light's surface; +infinity for infinite lights

    bool valid() const { return pdf > 0; }
};

class Light {
  public:
    virtual ~Light() = default;

    // Infinite lights (constant, envmap, sky) are seen by rays that escape the
    // scene; finite ones (spheres) by rays that hit them.
    virtual bool isInfinite() const = 0;
    // A point or a single direction (delta_lights.h): reached only by
    // next-event estimation, never by a ray. Its sample()'s pdf is 1 (a
    // probability, not a density), its pdf() 0, and the path tracer weights
    // its samples by 1, not by MIS; radiance() is its intensity or irradiance.
    virtual bool isDelta() const { return false; }
    // A direction towards the light from point p, with u uniform in [0, 1)^2.
    virtual LightSample sample(const Vec3& p, const std::array<double, 2>& u) const = 0;
    // Solid-angle density with which sample(p, .) returns wi (0 if it never does).
    virtual double pdf(const Vec3& p, const Vec3& wi) const = 0;
    // Infinite lights: radiance arriving from direction d (unit, pointing
    // away from the scene). Finite lights: the radiance of their surface
    // (the same everywhere).
    virtual Rgb radiance(const Vec3& d) const = 0;
    // For finite lights: distance along the ray (org, unit dir) to the first
    // intersection with the light's surface in (0, tMax), or a negative
    // value. Infinite lights return a negative value.
    virtual double intersect(const Vec3& org, const Vec3& dir, double tMax) const = 0;
    // The power the light sends into a scene of radius `sceneRadius` (pbrt's
    // Phi): pi A L for a surface of area A and radiance L; pi^2 4 R^2 times
    // the average radiance over directions for an infinite light (what
    // crosses a disc of radius R facing each direction). For the "power"
    // light sampler (light_sampler.h).
    virtual Rgb power(double sceneRadius) const = 0;
};

// The radiance of an infinite light averaged over the sphere of directions
// (a quadrature of radiance(d), 256 x 128 cells in (phi, cos theta)).
Rgb averageRadiance(const Light& infinite);

// A value as `os << value` writes it (a Vec3, an Rgb, a number), for the
// lights' error messages.
template <typename T>
std::string streamedText(const T& value) {
    std::ostringstream s;
    s << value;
    return s.str();
}

// For light constructors: InputError "<light>: radiance (r, g, b) must be
// finite and >= 0 in every channel" unless it is.
void checkLightRadiance(const Rgb& radiance, std::string_view light);

// One light of a scene file, as read and validated: what the scene writes,
// hashes and builds of it.
class LightDesc {
  public:
    virtual ~LightDesc() = default;

    // The registered type's name ("sphere").
    virtual const char* type() const = 0;
    // Its keys but "type", every one written (defaults included), file paths
    // as stored: readLight(params() + type) gives back an equal description.
    virtual nlohmann::json params() const = 0;
    // The files the light reads: (its key, the resolved path), for the
    // scene's inputs and hash.
    virtual std::vector<std::pair<std::string, std::string>> files() const { return {}; }
    // The light (InputError for a file that cannot be read or a bad value).
    virtual std::unique_ptr<Light> create() const = 0;

    // This description as its own type (std::logic_error for another).
    template <typename T>
    const T& as() const {
        const T* typed = dynamic_cast<const T*>(this);
        if (!typed)
            throw std::logic_error(std::string("a \"") + type() + "\" light is not a " +
                                   typeid(T).name());
        return *typed;
    }
};

struct LightType {
    const char* name;
    // Reads a light object whose "type" is `name`: r.allowKeys with every
    // key of the type (and "type"), then its values; relative file names
    // resolve against `baseDir`. InputError (through r) for anything wrong.
    std::shared_ptr<const LightDesc> (*read)(JsonObjectReader& r, const std::string& baseDir);
};

// Every registered light type, in the order the scene format lists them.
const std::vector<LightType>& lightTypes();

// A light object of a scene file: its "type" (one of lightTypes()), then
// the type's reader.
std::shared_ptr<const LightDesc> readLight(JsonObjectReader r, const std::string& baseDir);
// params() with the "type" key.
nlohmann::json toJson(const LightDesc& light);

}  // namespace weft::render
