#include "weft/render/path_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace weft::render {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

double powerHeuristic(double a, double b) {
    const double a2 = a * a, b2 = b * b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.0;
}

// The BSDF at one hit for the incident direction of the path, in its shading
// frame; world directions in and out.
class ShadingPoint {
  public:
    // `throughput`: the path's, which the BSDF may pick its lobes by (core/bsdf.h).
    ShadingPoint(const Scene& scene, const TubeHit& hit, const Vec3& wiWorld, const Rgb& throughput)
        : frame_(scene.shadingFrame(hit)),
          slice_(scene.bsdf(hit.material), frame_.toLocal(wiWorld), throughput) {}
    // eval and pdf at wo in one call.
    BsdfEval evalPdf(const Vec3& wo) const { return slice_.evalPdf(frame_.toLocal(wo)); }
    // A sample with wo in world space.
    BsdfSample sample(const BsdfSampleInput& u, Rng& rng) const {
        BsdfSample s = slice_.sample(u, rng);
        s.wo = normalize(frame_.fromLocal(s.wo));
        return s;
    }

  private:
    Frame frame_;
    BsdfSlice slice_;
};

// Nearest finite light hit by the ray before tMax: its index and distance.
int nearestFiniteLight(const Scene& scene, const Vec3& org, const Vec3& dir, double tMax,
                       double* distance) {
    int found = -1;
    const auto& lights = scene.lights();
    for (size_t i = 0; i < lights.size(); ++i) {
        if (lights[i]->isInfinite()) continue;
        const double t = lights[i]->intersect(org, dir, tMax);
        if (t > 0 && t < tMax) tMax = t, found = static_cast<int>(i), *distance = t;
    }
    return found;
}

// Next-event estimation from light `pick` (chosen with probability
// `pickPdf`): one light sample, its shadow ray (blocked by tubes and the other
// finite lights), weighted against BSDF sampling by the power heuristic.
Rgb directLight(const Scene& scene, const ShadingPoint& bsdf, const TubeHit& hit, int pick,
                double pickPdf, SampleStream& stream, PathCounters& counters) {
    const auto& lights = scene.lights();
    const Light& l = *lights[pick];
    const LightSample ls = l.sample(hit.point, stream.get2D());
    if (!ls.valid() || ls.radiance.isBlack()) return Rgb(0.0);
    // The shadow ray (up to just before the light's surface) before the BSDF,
    // so that an occluded sample costs no evaluation; the other order saved a
    // ray only where the BSDF is black, which the yarn's M lobe and the
    // fiber's R lobe almost never are. evalPdf draws no random numbers, so
    // the image is the same either way.
    const double tMax = std::isinf(ls.distance) ? kInfinity : ls.distance * (1 - 1e-6);
    ++counters.rays;
    if (scene.accel().occluded(hit.point, ls.wi, tMax, hit.id)) return Rgb(0.0);
    for (size_t i = 0; i < lights.size(); ++i)
        if (static_cast<int>(i) != pick && !lights[i]->isInfinite() &&
            lights[i]->intersect(hit.point, ls.wi, tMax) > 0)
            return Rgb(0.0);
    const BsdfEval e = bsdf.evalPdf(ls.wi);
    if (e.value.isBlack()) return Rgb(0.0);
    const double lightPdf = pickPdf * ls.pdf;
    return e.value * ls.radiance * (powerHeuristic(lightPdf, e.pdf) / lightPdf);
}

}  // namespace

Rgb pathRadiance(const Scene& scene, const Vec3& orgIn, const Vec3& dirIn, SampleStream& stream,
                 const PathTracerOptions& options, PathCounters& counters, FirstHit* first) {
    const auto& lights = scene.lights();
    const LightSampler& lightSampler = scene.lightSampler();
    const bool nee = options.nextEventEstimation && !lights.empty();

    Rgb radiance(0.0), throughput(1.0);
    Vec3 org = orgIn, dir = dirIn;
    TubeId origin;
    // Density with which the last BSDF sample chose `dir`; 0 after the camera or a delta lobe.
    double lastPdf = 0;
    bool countEmissionFully = true;
    ++counters.paths;

    for (int depth = 0;; ++depth) {
        TubeHit hit;
        ++counters.rays;
        const bool hitTube = scene.accel().intersect(org, dir, kInfinity, origin, &hit);
        double lightDistance = 0;
        const int light =
            nearestFiniteLight(scene, org, dir, hitTube ? hit.t : kInfinity, &lightDistance);

        // Emission seen by this ray: a sphere light in front of the tube, or
        // every infinite light if it escapes.
        // The MIS weight uses the probability with which NEE picks light i.
        auto addEmission = [&](size_t i, const Rgb& le) {
            double weight = 1.0;
            if (nee && !countEmissionFully)
                weight = powerHeuristic(lastPdf, lightSampler.pmf(i) * lights[i]->pdf(org, dir));
            radiance += throughput * le * weight;
        };
        if (light >= 0) {
            addEmission(static_cast<size_t>(light), lights[light]->radiance(dir));
            break;
        }
        if (!hitTube) {
            for (size_t i = 0; i < lights.size(); ++i)
                if (lights[i]->isInfinite()) addEmission(i, lights[i]->radiance(dir));
            break;
        }
        if (depth >= options.maxDepth) {
            ++counters.truncated;
            break;
        }

        const ShadingPoint bsdf(scene, hit, -dir, throughput);
        if (depth == 0 && first) {
            first->hit = true;
            first->depth = hit.t;
            first->normal = dot(hit.normal, dir) > 0 ? -hit.normal : hit.normal;
            first->geometry = hit.id.geometry;
        }

        if (nee) {
            double pickPdf = 0;
            const int pick = lightSampler.sample(stream.get1D(), &pickPdf);
            radiance += throughput * directLight(scene, bsdf, hit, pick, pickPdf, stream, counters);
        }

        const double lobeU = stream.get1D();
        const std::array<double, 2> dirU = stream.get2D();
        const BsdfSampleInput u = {lobeU, dirU[0], dirU[1]};
        const BsdfSample s = bsdf.sample(u, stream.rng());
        if (depth == 0 && first && s.valid()) first->albedo = s.weight;
        if (!s.valid() || s.weight.isBlack()) break;
        throughput *= s.weight;
        if (!throughput.isFinite()) break;
        lastPdf = s.pdf;
        countEmissionFully = s.isDelta;
        org = hit.point;
        dir = s.wo;
        origin = hit.id;

        if (depth + 1 >= options.rouletteDepth) {
            const double survive = std::min(1.0, throughput.maxComponent());
            if (stream.get1D() >= survive) break;
            throughput = throughput / survive;
        }
    }
    return radiance;
}

}  // namespace weft::render
