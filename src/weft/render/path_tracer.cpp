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
    const Frame& frame() const { return frame_; }
    const BsdfSlice& slice() const { return slice_; }
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

// What next-event estimation needs from the BSDF: a light sample that
// passed its shadow ray, waiting for the BSDF's evalPdf at `wi`.
struct LightSampleAtHit {
    bool pending = false;
    Vec3 wi;  // world direction to the light
    Rgb radiance;
    double lightPdf = 0;  // the pick's probability times the light's density
    bool delta = false;   // a point or directional light: no BSDF sample finds it
};

// Next-event estimation's light part: one light picked by the scene's light
// sampler, one direction from its sample(), its shadow ray (blocked by tubes
// and by the other finite lights). The shadow ray comes before the BSDF, so
// that an occluded sample costs no evaluation; the other order saved a ray
// only where the BSDF is black, which the yarn's M lobe and the fiber's R
// lobe almost never are. evalPdf draws no random numbers, so the image is
// the same either way.
LightSampleAtHit sampleLightAtHit(const Scene& scene, const TubeHit& hit, SampleStream& stream,
                                  PathCounters& counters) {
    const auto& lights = scene.lights();
    double pickPdf = 0;
    const int pick = scene.lightSampler().sample(stream.get1D(), &pickPdf);
    const Light& l = *lights[pick];
    const LightSample ls = l.sample(hit.point, stream.get2D());
    if (!ls.valid() || ls.radiance.isBlack()) return {};
    const double tMax = std::isinf(ls.distance) ? kInfinity : ls.distance * (1 - 1e-6);
    ++counters.rays;
    if (scene.accel().occluded(hit.point, ls.wi, tMax, hit.id)) return {};
    for (size_t i = 0; i < lights.size(); ++i)
        if (static_cast<int>(i) != pick && !lights[i]->isInfinite() &&
            lights[i]->intersect(hit.point, ls.wi, tMax) > 0)
            return {};
    return {true, ls.wi, ls.radiance, pickPdf * ls.pdf, l.isDelta()};
}

// The light sample's contribution with the BSDF's value and density there,
// weighted against BSDF sampling by the power heuristic (by 1 for a delta
// light, which BSDF sampling cannot reach).
Rgb directLight(const LightSampleAtHit& light, const BsdfEval& e) {
    if (!light.pending || e.value.isBlack()) return Rgb(0.0);
    const double weight = light.delta ? 1.0 : powerHeuristic(light.lightPdf, e.pdf);
    return e.value * light.radiance * (weight / light.lightPdf);
}

// One path between its scattering events: where its next ray starts, what
// it carries, and how the last BSDF sample chose its direction.
struct PathState {
    Vec3 org, dir;
    TubeId origin;
    Rgb radiance{0.0}, throughput{1.0};
    // Density with which the last BSDF sample chose `dir`; 0 after the camera or a delta lobe.
    double lastPdf = 0;
    bool countEmissionFully = true;
};

// Traces the path's next ray and adds the emission it sees: a sphere light
// in front of the tube, or every infinite light but a directional one if it escapes (the MIS
// weight uses the probability with which NEE picks light i). True when the
// ray hit a tube that scatters the path further (in *hit); false when the
// path ends here (a light, the sky, or maxDepth events: counted truncated).
bool traceToNextHit(const Scene& scene, PathState& p, int depth, bool nee,
                    const PathTracerOptions& options, PathCounters& counters, TubeHit* hit) {
    const auto& lights = scene.lights();
    ++counters.rays;
    const bool hitTube = scene.accel().intersect(p.org, p.dir, kInfinity, p.origin, hit);
    double lightDistance = 0;
    const int light =
        nearestFiniteLight(scene, p.org, p.dir, hitTube ? hit->t : kInfinity, &lightDistance);
    auto addEmission = [&](size_t i, const Rgb& le) {
        double weight = 1.0;
        if (nee && !p.countEmissionFully)
            weight = powerHeuristic(p.lastPdf,
                                    scene.lightSampler().pmf(i) * lights[i]->pdf(p.org, p.dir));
        p.radiance += p.throughput * le * weight;
    };
    if (light >= 0) {
        addEmission(static_cast<size_t>(light), lights[light]->radiance(p.dir));
        return false;
    }
    if (!hitTube) {
        for (size_t i = 0; i < lights.size(); ++i)
            if (lights[i]->isInfinite() && !lights[i]->isDelta())
                addEmission(i, lights[i]->radiance(p.dir));
        return false;
    }
    if (depth >= options.maxDepth) {
        ++counters.truncated;
        return false;
    }
    return true;
}

void recordFirstHit(const TubeHit& hit, const Vec3& dir, FirstHit* first) {
    first->hit = true;
    first->depth = hit.t;
    first->normal = dot(hit.normal, dir) > 0 ? -hit.normal : hit.normal;
    first->geometry = hit.id.geometry;
}

// The three numbers of the BSDF sample: lobe, then direction.
BsdfSampleInput bsdfSampleInput(SampleStream& stream) {
    const double lobeU = stream.get1D();
    const std::array<double, 2> dirU = stream.get2D();
    return {lobeU, dirU[0], dirU[1]};
}

// Continues the path with the BSDF sample `s` (wo in world space) drawn at
// `hit`, then Russian roulette; false when the path ends.
bool continuePath(PathState& p, const TubeHit& hit, const BsdfSample& s, int depth,
                  SampleStream& stream, const PathTracerOptions& options, FirstHit* first) {
    if (depth == 0 && first && s.valid()) first->albedo = s.weight;
    if (!s.valid() || s.weight.isBlack()) return false;
    p.throughput *= s.weight;
    if (!p.throughput.isFinite()) return false;
    p.lastPdf = s.pdf;
    p.countEmissionFully = s.isDelta;
    p.org = hit.point;
    p.dir = s.wo;
    p.origin = hit.id;
    if (depth + 1 >= options.rouletteDepth) {
        const double survive = std::min(1.0, p.throughput.maxComponent());
        if (stream.get1D() >= survive) return false;
        p.throughput = p.throughput / survive;
    }
    return true;
}

// An event of a BSDF whose spread part leaves elsewhere (ExitSpread,
// core/bsdf.h) between its halves: the exit offset, the exit point and its
// frame, and the light sample there.
struct SplitEvent {
    SpreadOffset offset;
    TubeHit exit;
    Frame exitFrame;
    LightSampleAtHit atExit;
    Vec3 woExit;  // atExit.wi in the exit frame
};

// The split event's first half, after the light sample at the hit
// (`light`; `surfaceAtLight`: evalSurface at its direction, unused where it
// is not pending) and the event's sample input: next-event estimation at the
// hit with the surface part; three more numbers give the exit point; one
// more light pick and light sample there.
SplitEvent beginSplit(const Scene& scene, const ExitSpread& spread, const BsdfIncident& in,
                      const TubeHit& hit, const LightSampleAtHit& light,
                      const BsdfEval& surfaceAtLight, PathState& p, bool nee, SampleStream& stream,
                      PathCounters& counters) {
    if (light.pending) p.radiance += p.throughput * directLight(light, surfaceAtLight);
    SplitEvent split;
    const double uChannel = stream.get1D();
    const std::array<double, 2> uOffset = stream.get2D();
    split.offset = spread.sampleOffset(in, {uChannel, uOffset[0], uOffset[1]});
    split.exit = scene.accel().exitPoint(hit, split.offset.dz, split.offset.dpsi);
    split.exitFrame = scene.shadingFrame(split.exit);
    if (nee) {
        split.atExit = sampleLightAtHit(scene, split.exit, stream, counters);
        if (split.atExit.pending) split.woExit = split.exitFrame.toLocal(split.atExit.wi);
    }
    return split;
}

// The second half, with the spread part at the exit point's light sample
// (evalSpread at woExit; unused where that sample is not pending) and the
// continuation (sampleEvent): next-event estimation at the exit point, then
// the path goes on from the hit or from the exit point. False when the
// path ends.
bool finishSplit(const SplitEvent& split, const BsdfEval& spreadAtLight, SpreadSample next,
                 const Frame& frame, const TubeHit& hit, PathState& p, int depth,
                 SampleStream& stream, const PathTracerOptions& options, FirstHit* first) {
    if (split.atExit.pending)
        p.radiance += p.throughput * split.offset.weight * directLight(split.atExit, spreadAtLight);
    next.sample.wo = normalize((next.spread ? split.exitFrame : frame).fromLocal(next.sample.wo));
    if (!next.spread) return continuePath(p, hit, next.sample, depth, stream, options, first);
    next.sample.weight *= split.offset.weight;
    return continuePath(p, split.exit, next.sample, depth, stream, options, first);
}

// One split event of one path: both halves with the single calls.
bool splitEvent(const Scene& scene, const ExitSpread& spread, const BsdfIncident& in,
                const Frame& frame, const TubeHit& hit, const LightSampleAtHit& light,
                const BsdfSampleInput& u, PathState& p, int depth, bool nee, SampleStream& stream,
                const PathTracerOptions& options, PathCounters& counters, FirstHit* first) {
    const BsdfEval surfaceAtLight =
        light.pending ? spread.evalSurface(in, frame.toLocal(light.wi)) : BsdfEval{};
    const SplitEvent split =
        beginSplit(scene, spread, in, hit, light, surfaceAtLight, p, nee, stream, counters);
    const BsdfEval spreadAtLight =
        split.atExit.pending ? spread.evalSpread(in, split.woExit) : BsdfEval{};
    return finishSplit(split, spreadAtLight, spread.sampleEvent(in, u, stream.rng()), frame, hit, p,
                       depth, stream, options, first);
}

// The ExitSpread of a prepared incident's BSDF where its event splits, else null.
const ExitSpread* splitting(const Bsdf& bsdf, const BsdfIncident& in) {
    const ExitSpread* spread = bsdf.exitSpread();
    return spread && spread->splits(in) ? spread : nullptr;
}

}  // namespace

Rgb pathRadiance(const Scene& scene, const Vec3& orgIn, const Vec3& dirIn, SampleStream& stream,
                 const PathTracerOptions& options, PathCounters& counters, FirstHit* first) {
    const bool nee = options.nextEventEstimation && !scene.lights().empty();
    PathState p;
    p.org = orgIn;
    p.dir = dirIn;
    ++counters.paths;
    for (int depth = 0;; ++depth) {
        TubeHit hit;
        if (!traceToNextHit(scene, p, depth, nee, options, counters, &hit)) break;
        const ShadingPoint bsdf(scene, hit, -p.dir, p.throughput);
        if (depth == 0 && first) recordFirstHit(hit, p.dir, first);
        const ExitSpread* spread = splitting(bsdf.slice().bsdf(), bsdf.slice().incident());
        LightSampleAtHit light;
        if (nee) {
            light = sampleLightAtHit(scene, hit, stream, counters);
            if (light.pending && !spread)
                p.radiance += p.throughput * directLight(light, bsdf.evalPdf(light.wi));
        }
        if (spread) {
            if (!splitEvent(scene, *spread, bsdf.slice().incident(), bsdf.frame(), hit, light,
                            bsdfSampleInput(stream), p, depth, nee, stream, options, counters,
                            first))
                break;
            continue;
        }
        const BsdfSample s = bsdf.sample(bsdfSampleInput(stream), stream.rng());
        if (!continuePath(p, hit, s, depth, stream, options, first)) break;
    }
    return p.radiance;
}

void pathRadianceBatch(const Scene& scene, std::span<PathQuery> queries,
                       const PathTracerOptions& options, PathCounters& counters) {
    const bool nee = options.nextEventEstimation && !scene.lights().empty();
    // A path's state at its current scattering event.
    struct Event {
        TubeHit hit;
        Frame frame;
        BsdfIncident incident;
        Vec3 wiLocal, woLocal;
        LightSampleAtHit light;
        BsdfEval eval;
        BsdfSampleInput u;
        BsdfSample sample;
        const ExitSpread* spread = nullptr;  // the event splits (ExitSpread)
        SplitEvent split;
        BsdfEval spreadAtLight;
        SpreadSample next;
    };
    const size_t n = queries.size();
    std::vector<PathState> paths(n);
    std::vector<Event> events(n);
    std::vector<size_t> alive(n);
    for (size_t k = 0; k < n; ++k) {
        paths[k].org = queries[k].org;
        paths[k].dir = queries[k].dir;
        alive[k] = k;
    }
    counters.paths += n;
    // The paths at an event, grouped by BSDF (first-seen order); scratch
    // arrays for one group's batch call.
    std::vector<std::pair<const Bsdf*, std::vector<size_t>>> groups;
    std::vector<Vec3> vecs;
    std::vector<BsdfIncident*> incidents;
    std::vector<const BsdfIncident*> constIncidents;
    std::vector<BsdfEval> evals;
    std::vector<BsdfSampleInput> inputs;
    std::vector<Rng*> rngs;
    std::vector<BsdfSample> samples;
    std::vector<SpreadSample> spreadSamples;
    std::vector<size_t> pending;
    // One group's members whose event wo(event) gives a direction, in one
    // call(incidents, directions, count, results); each result into its
    // event's `result`.
    auto evalBatch = [&](const std::vector<size_t>& members, auto&& wo, auto&& call,
                         BsdfEval Event::*result) {
        vecs.clear();
        constIncidents.clear();
        pending.clear();
        for (const size_t k : members)
            if (const Vec3* w = wo(events[k])) {
                pending.push_back(k);
                vecs.push_back(*w);
                constIncidents.push_back(&events[k].incident);
            }
        if (pending.empty()) return;
        evals.resize(pending.size());
        call(constIncidents.data(), vecs.data(), pending.size(), evals.data());
        for (size_t j = 0; j < pending.size(); ++j) events[pending[j]].*result = evals[j];
    };
    // One group's members whose event splits (or not), with their sample
    // inputs and generators, in one call(incidents, inputs, generators,
    // count, scratch); each sample into its event's `result`.
    auto sampleBatch = [&](const std::vector<size_t>& members, bool split, auto&& call,
                           auto& scratch, auto Event::*result) {
        constIncidents.clear();
        inputs.clear();
        rngs.clear();
        pending.clear();
        for (const size_t k : members) {
            if ((events[k].spread != nullptr) != split) continue;
            pending.push_back(k);
            constIncidents.push_back(&events[k].incident);
            inputs.push_back(events[k].u);
            rngs.push_back(&queries[k].stream->rng());
        }
        if (pending.empty()) return;
        scratch.resize(pending.size());
        call(constIncidents.data(), inputs.data(), rngs.data(), pending.size(), scratch.data());
        for (size_t j = 0; j < pending.size(); ++j) events[pending[j]].*result = scratch[j];
    };
    for (int depth = 0; !alive.empty(); ++depth) {
        // Every path's next ray, and its BSDF.
        for (auto& group : groups) group.second.clear();
        size_t kept = 0;
        for (const size_t k : alive) {
            PathState& p = paths[k];
            Event& e = events[k];
            if (!traceToNextHit(scene, p, depth, nee, options, counters, &e.hit)) continue;
            e.frame = scene.shadingFrame(e.hit);
            e.wiLocal = e.frame.toLocal(-p.dir);
            e.incident.setImportance(p.throughput);  // prepareBatch sets the rest
            if (depth == 0 && queries[k].first) recordFirstHit(e.hit, p.dir, queries[k].first);
            const Bsdf* bsdf = &scene.bsdf(e.hit.material);
            auto group = std::find_if(groups.begin(), groups.end(),
                                      [&](const auto& g) { return g.first == bsdf; });
            if (group == groups.end()) group = groups.insert(groups.end(), {bsdf, {}});
            group->second.push_back(k);
            alive[kept++] = k;
        }
        alive.resize(kept);
        // Each group's calls in one batch; vecs, incidents, ... hold its members' arguments.
        auto forEachGroup = [&](auto&& call) {
            for (const auto& [bsdf, members] : groups)
                if (!members.empty()) call(*bsdf, members);
        };
        forEachGroup([&](const Bsdf& bsdf, const std::vector<size_t>& members) {
            vecs.clear();
            incidents.clear();
            for (const size_t k : members) {
                vecs.push_back(events[k].wiLocal);
                incidents.push_back(&events[k].incident);
            }
            bsdf.prepareBatch(vecs.data(), incidents.data(), members.size());
            for (const size_t k : members) events[k].spread = splitting(bsdf, events[k].incident);
        });
        if (nee) {
            for (const size_t k : alive) {
                Event& e = events[k];
                e.light = sampleLightAtHit(scene, e.hit, *queries[k].stream, counters);
                if (e.light.pending) e.woLocal = e.frame.toLocal(e.light.wi);
            }
            forEachGroup([&](const Bsdf& bsdf, const std::vector<size_t>& members) {
                // Whole events with evalPdf, split ones with their surface part.
                evalBatch(
                    members,
                    [](const Event& e) {
                        return e.light.pending && !e.spread ? &e.woLocal : nullptr;
                    },
                    [&](auto... args) { bsdf.evalPdfBatch(args...); }, &Event::eval);
                evalBatch(
                    members,
                    [](const Event& e) {
                        return e.light.pending && e.spread ? &e.woLocal : nullptr;
                    },
                    [&](auto... args) { bsdf.exitSpread()->evalSurfaceBatch(args...); },
                    &Event::eval);
            });
            for (const size_t k : alive) {
                const Event& e = events[k];
                if (e.light.pending && !e.spread)
                    paths[k].radiance += paths[k].throughput * directLight(e.light, e.eval);
            }
        }
        for (const size_t k : alive) events[k].u = bsdfSampleInput(*queries[k].stream);
        forEachGroup([&](const Bsdf& bsdf, const std::vector<size_t>& members) {
            sampleBatch(
                members, false, [&](auto... args) { bsdf.sampleBatch(args...); }, samples,
                &Event::sample);
        });
        // The split events: each path's exit point and light sample there,
        // then each group's spread parts and continuations in batches.
        for (const size_t k : alive) {
            Event& e = events[k];
            if (e.spread)
                e.split = beginSplit(scene, *e.spread, e.incident, e.hit,
                                     nee ? e.light : LightSampleAtHit{}, e.eval, paths[k], nee,
                                     *queries[k].stream, counters);
        }
        forEachGroup([&](const Bsdf& bsdf, const std::vector<size_t>& members) {
            const ExitSpread* spread = bsdf.exitSpread();
            if (!spread) return;
            evalBatch(
                members,
                [](const Event& e) {
                    return e.spread && e.split.atExit.pending ? &e.split.woExit : nullptr;
                },
                [&](auto... args) { spread->evalSpreadBatch(args...); }, &Event::spreadAtLight);
            sampleBatch(
                members, true, [&](auto... args) { spread->sampleEventBatch(args...); },
                spreadSamples, &Event::next);
        });
        kept = 0;
        for (const size_t k : alive) {
            Event& e = events[k];
            if (e.spread) {
                if (finishSplit(e.split, e.spreadAtLight, e.next, e.frame, e.hit, paths[k], depth,
                                *queries[k].stream, options, queries[k].first))
                    alive[kept++] = k;
                continue;
            }
            e.sample.wo = normalize(e.frame.fromLocal(e.sample.wo));
            if (continuePath(paths[k], e.hit, e.sample, depth, *queries[k].stream, options,
                             queries[k].first))
                alive[kept++] = k;
        }
        alive.resize(kept);
    }
    for (size_t k = 0; k < n; ++k) queries[k].radiance = paths[k].radiance;
}

}  // namespace weft::render
