// weft/render/path_tracer.h — unidirectional path tracing for cloth (issue 7, docs/design.md 8).
//
// radiance() estimates the radiance arriving at `org` from direction -dir:
//   - at every tube hit, next-event estimation: one light picked by the
//     scene's light sampler (light_sampler.h: uniform, by power or by given
//     weights), one direction from its sample(), a shadow ray (blocked by tubes and by
//     the other finite lights), weighted against BSDF sampling by the power
//     heuristic (Veach 1997; pbrt-v4 PathIntegrator);
//   - then one BSDF sample continues the path. The BSDF is prepared with the
//     path throughput as its channel importance (core/bsdf.h): the fiber
//     BCSDF picks R or TT by it, which keeps fiber-mode throughputs bounded
//     over hundreds of events. Rays that escape see every infinite light,
//     rays that hit a sphere light see it; both weighted by
//     the power heuristic against the light's NEE density (the sampler's
//     pick probability times Light::pdf), or fully after a delta (T lobe) or camera
//     vertex. With NEE off, emission is always counted fully (pure BSDF
//     sampling: the same expectation, used by the consistency test);
//   - a BSDF whose multiply scattered part leaves elsewhere (ExitSpread,
//     core/bsdf.h: a yarn model with exit offsets, docs/exit-point.md)
//     splits its event: an exit point on the same tube from three more
//     numbers (TubeAccel::exitPoint), next-event estimation at the hit with
//     the surface part and at the exit point with the spread part in the
//     exit point's frame (one more light pick and 2D light sample), then one
//     continuation, from the hit or from the exit point. A model without
//     the table draws and computes exactly as before;
//   - the yarn BSDF's T lobe (a delta, wo = -wi) continues straight through
//     the ply it hit: the continuation ray leaves that ply (tube_accel.h drops
//     its interior);
//   - Russian roulette from `rouletteDepth` scattering events on, with
//     survival probability min(1, max channel of the path throughput) (an
//     unbiased estimator: survivors are divided by it);
//   - at most `maxDepth` scattering events (the scene's render.max_depth); a
//     path still carrying light there is cut and counted (PathCounters::
//     truncated): its further light is missing from the image. Near-white
//     fibers need many events (cotton: about 13 fiber events per ply visit,
//     so 100 cut 10 % of a cotton cloth's light in fiber mode); the default
//     1000 is the gather's (gather.h), whose RDM the neural model learns.
// Shading frames: neural mode, the yarn frame of docs/design.md 2 (t = segment
// tangent, n = outward tube normal, b = t x n); fiber mode, the fiber frame
// with the tangent as +x (FiberBcsdf); both from Scene::shadingFrame.
// All random numbers come from the caller's SampleStream (core/sample_stream.h):
// per path vertex a 1D light pick, a 2D light sample, a 1D lobe choice and a
// 2D BSDF direction, then a 1D roulette draw; a BSDF's own further numbers
// come from the stream's Rng. A path is a function of (scene, ray, stream).
#pragma once

#include <cstdint>
#include <span>

#include "weft/core/rgb.h"
#include "weft/core/rng.h"
#include "weft/core/sample_stream.h"
#include "weft/core/vec.h"
#include "weft/render/scene.h"

namespace weft::render {

struct PathTracerOptions {
    int maxDepth = 1000;
    bool nextEventEstimation = true;
    int rouletteDepth = 3;
};

struct PathCounters {
    uint64_t rays = 0;  // closest-hit and shadow queries
    uint64_t paths = 0;
    uint64_t truncated = 0;  // paths cut at maxDepth
};

// What a camera ray met first, for the render passes (renderer.h, issue 43):
// filled by pathRadiance when asked for.
struct FirstHit {
    bool hit = false;  // a tube or an object (not a light, not the sky)
    double depth = 0;  // distance along the unit ray to the hit
    Vec3 normal;       // world shading normal there, turned towards the ray's origin
    // The weight of the BSDF sample drawn there (eval / pdf, 0 when absorbed):
    // an unbiased estimate of the BSDF's albedo for that incident direction.
    Rgb albedo;
    uint32_t geometry = kNoTube;  // TubeHit::id.geometry
};

// `first`, when not null, receives the first hit of the path.
Rgb pathRadiance(const Scene& scene, const Vec3& org, const Vec3& dir, SampleStream& stream,
                 const PathTracerOptions& options, PathCounters& counters,
                 FirstHit* first = nullptr);

// One path of a batch: its camera ray and sample stream in (and `first`, as
// for pathRadiance), its radiance out.
struct PathQuery {
    Vec3 org, dir;
    SampleStream* stream = nullptr;
    FirstHit* first = nullptr;
    Rgb radiance;
};

// pathRadiance for many paths at once (issue 45): the paths advance one
// scattering event at a time together, and each event's BSDF calls are made
// in one batch per BSDF (Bsdf::prepareBatch, evalPdfBatch, sampleBatch, and
// a split event's ExitSpread::evalSpreadBatch, sampleEventBatch: the yarn
// BSDF's networks then run a query per SIMD lane). Each path draws the
// same numbers from its stream in the same order as pathRadiance, and the
// batches give the single calls' bits, so every query's radiance and first
// hit, and the counters' totals, are bit for bit pathRadiance's
// (render_test holds them to it).
void pathRadianceBatch(const Scene& scene, std::span<PathQuery> queries,
                       const PathTracerOptions& options, PathCounters& counters);

}  // namespace weft::render
