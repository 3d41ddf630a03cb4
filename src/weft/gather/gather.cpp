#include "weft/gather/gather.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "weft/core/curves.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_reader.h"
#include "weft/core/limits.h"
#include "weft/core/math.h"
#include "weft/core/npy.h"
#include "weft/core/progress.h"
#include "weft/core/rng.h"
#include "weft/core/sampling.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/gather/colour_paths.h"
#include "weft/gather/ply_tracer.h"

namespace weft {

namespace {

// Fixed-point accumulators (GatherSums::toFixed): associative sums,
// thread-count independent results.
constexpr double kFixedScale = GatherSums::kFixedScale;

void atomicAdd(int64_t& cell, int64_t v) {
    if (v != 0) std::atomic_ref<int64_t>(cell).fetch_add(v, std::memory_order_relaxed);
}

constexpr int64_t kChunk = 1024;  // paths per task

PlyGeometry gatherPly(const GatherOptions& o) {
    // R = 1: everything is scale-invariant.
    return generatePly(o.ply, 1.0, 1.0, o.placementSeed());
}

// Zero sums and the description of the traced ply.
GatherSums zeroSums(const GatherOptions& o, const PlyGeometry& ply,
                    const PeriodicPlyTracer& tracer) {
    const size_t nIn = o.bins.incidentCount(), nOut = o.bins.outgoingCount();
    GatherSums s;
    s.bins = o.bins;
    s.count.assign(nIn, 0);
    s.countT.assign(nIn, 0);
    s.sumTruncated.assign(nIn * 3, 0);
    s.sumExitDistance.assign((kExitDistanceBins + 1) * 3, 0);
    s.sumExitOffset.assign(kExitOffsetCells * kExitOffsetSlots * 3, 0);
    s.sumR.assign(nIn * nOut * 3, 0);
    s.sumM.assign(nIn * nOut * 3, 0);
    s.sumMExit.assign(nIn * nOut * 3, 0);
    s.depth.assign(static_cast<size_t>(o.maxDepth) + 2, 0);
    s.plyLines = tracer.centreLines();
    s.period = tracer.period();
    s.fiberRadius = ply.fiberRadius;
    s.segments = tracer.segmentCount();
    s.embreeBytes = tracer.embreeBytes();
    return s;
}

}  // namespace

void GatherOptions::validate() const {
    // Each path adds a weight of at most 1 to a cell, so 2^31 paths cannot
    // overflow the fixed-point accumulators.
    checkRange("paths =", paths, 1, kMaxPaths, " (the fixed-point sums hold 2^31 paths)");
    checkRange("max depth =", maxDepth, 1, 1000000);
    checkRange("threads =", threads, 0, 1024, " (0: all cores)");
    shard.validate(paths, "--shard", "paths");
    PeriodicPlyTracer::validateSegmentsPerTwist(segmentsPerTwist);
    fiber.validate();
    ply.validate();
    // The explicit ply within the memory budget before its fibers are placed
    // (a million fibers take seconds): radius R = 1, r = R sqrt(rho / N) (generatePly).
    PeriodicPlyTracer::layout(ply, 1.0, std::sqrt(ply.density / ply.fibers), segmentsPerTwist,
                              static_cast<size_t>(ply.fibers));
    bins.validate();
    if (anyColour)
        checkMemoryBudget(static_cast<double>(shard.end(paths) - shard.begin(paths)) *
                              (2.0 * sizeof(ColourPath)),
                          "the recorded paths of an any-colour gather (" +
                              std::to_string(paths) + " paths)");
    // The R and M maps: int64 sums while gathering, float results, and their
    // copies on the way to disk: about 96 bytes per cell.
    checkMemoryBudget(static_cast<double>(bins.incidentCount()) * bins.outgoingCount() * 96.0,
                      "the RDM's bins (" + bins.toString() + ")");
}

GatherSums emptyGatherSums(const GatherOptions& o) {
    o.validate();
    const PlyGeometry ply = gatherPly(o);
    const PeriodicPlyTracer tracer(ply, o.segmentsPerTwist);
    return zeroSums(o, ply, tracer);
}

GatherSums gatherSums(const GatherOptions& o) {
    o.validate();
    const auto start = std::chrono::steady_clock::now();
    const FiberBcsdf fiber(o.fiber);
    // Any colour: lobes chosen as by a white fiber, weighted per lobe (colour_paths.h).
    std::optional<FiberBcsdf> colourBlind;
    if (o.anyColour) colourBlind.emplace(colourBlindFiber(o.fiber));
    const PlyGeometry ply = gatherPly(o);
    const PeriodicPlyTracer tracer(ply, o.segmentsPerTwist);
    const RdmBins& bins = o.bins;
    const size_t nOut = bins.outgoingCount();
    GatherSums sums = zeroSums(o, ply, tracer);
    sums.firstPath = o.shard.begin(o.paths);
    sums.endPath = o.shard.end(o.paths);
    std::atomic<int64_t> rays{0}, axial{0}, depthSum{0};

    const double period = tracer.period();
    const int64_t firstPath = sums.firstPath, endPath = sums.endPath;
    const int64_t chunks = (endPath - firstPath + kChunk - 1) / kChunk;
    // Per chunk, so that their concatenation is in path order for any thread count.
    std::vector<std::vector<ColourPath>> chunkColourPaths(o.anyColour ? chunks : 0);
    Progress progress(o.shard.whole() ? "gather" : "gather " + o.shard.toString(),
                      static_cast<uint64_t>(endPath - firstPath), o.quiet);
    const int threads = o.threads > 0 ? o.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    const auto walkStart = std::chrono::steady_clock::now();
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int64_t>(0, chunks), [&](const auto& range) {
            for (int64_t chunk = range.begin(); chunk != range.end(); ++chunk) {
                const int64_t first = firstPath + chunk * kChunk,
                              last = std::min(endPath, first + kChunk);
                int64_t chunkRays = 0, chunkAxial = 0, chunkDepth = 0;
                for (int64_t k = first; k < last; ++k) {
                    // Path k's stream depends on (seed, k) alone, not on the shard.
                    Rng rng(static_cast<uint64_t>(k), o.seed);
                    // Entry point and frame (docs/design.md 5).
                    const double psi = kTwoPi * rng.uniform();
                    const Vec3 n{std::cos(psi), std::sin(psi), 0.0};
                    const Vec3 t{0.0, 0.0, 1.0};
                    const Frame entry = yarnFrame(t, n);
                    Vec3 org = n * ply.radius;
                    org.z = period * rng.uniform();
                    const double entryZ = org.z;
                    int periodShift = 0;  // twist periods crossed, for the exit distance
                    Vec3 exitPoint;
                    // wi uniform over the upper hemisphere: cos(theta) uniform.
                    const double uCosTheta = rng.uniform(), uPhi = rng.uniform();
                    const Vec3 wiLocal = sampleUniformHemisphere(uCosTheta, uPhi);
                    const size_t binIn = bins.incidentBin(wiLocal);
                    const size_t offsetCell = exitOffsetCell(wiLocal);
                    Vec3 dir = -entry.fromLocal(wiLocal);
                    // Any colour: weight = W0 C_TT^ttEvents.
                    Rgb weight(1.0);
                    int depth = 0, excluded = -1, ttEvents = 0;
                    bool truncatedPath = false;
                    for (;;) {
                        const PlyTraceHit hit = tracer.trace(org, dir, excluded);
                        chunkRays += hit.raysTraced;
                        periodShift += hit.periodShift;
                        if (hit.kind != PlyTraceHit::Kind::Fiber) {
                            chunkAxial += hit.kind == PlyTraceHit::Kind::ExitAxial;
                            exitPoint = hit.kind == PlyTraceHit::Kind::ExitSide
                                            ? hit.point
                                            : Vec3(0, 0, std::numeric_limits<double>::infinity());
                            break;
                        }
                        if (depth == o.maxDepth) {
                            truncatedPath = true;
                            break;
                        }
                        ++depth;
                        const Frame fiberFrame =
                            Frame::fromX(ply.fiberTangent(hit.fiber, hit.point.z));
                        const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
                        const Vec3 wiFiber = fiberFrame.toLocal(-dir);
                        BsdfSample s;
                        if (o.anyColour) {
                            BsdfIncident prepared;
                            colourBlind->prepare(wiFiber, prepared);
                            const auto& in = prepared.get<FiberBcsdf::Incident>();
                            s = colourBlind->sample(prepared, u, rng);
                            if (s.lobe == FiberBcsdf::kLobeR) {
                                s.weight = in.fresnel / in.probabilityR;
                            } else if (s.valid()) {
                                s.weight = (Rgb(1.0) - in.fresnel) / (1.0 - in.probabilityR);
                                ++ttEvents;
                            }
                        } else {
                            s = fiber.sample(wiFiber, u, rng);
                        }
                        if (!s.valid()) {
                            weight = Rgb();
                            break;
                        }
                        weight *= s.weight;
                        dir = normalize(fiberFrame.fromLocal(s.wo));
                        org = hit.point;
                        excluded = hit.fiber;
                    }
                    atomicAdd(sums.count[binIn], 1);
                    atomicAdd(sums.depth[truncatedPath ? o.maxDepth + 1 : depth], 1);
                    chunkDepth += depth;
                    if (depth == 0 && !truncatedPath) {
                        atomicAdd(sums.countT[binIn], 1);
                        continue;
                    }
                    ColourPath path;
                    path.incidentBin = static_cast<int32_t>(binIn);
                    path.ttEvents = ttEvents;
                    Vec3 woLocal;  // in the entry frame
                    if (truncatedPath) {
                        path.kind = ColourPath::Truncated;
                    } else {
                        woLocal = entry.toLocal(dir);
                        path.kind = depth == 1 && woLocal.z > 0 ? ColourPath::R : ColourPath::M;
                        path.outgoingBin = static_cast<int32_t>(bins.outgoingBin(woLocal));
                    }
                    if (o.anyColour)
                        for (int c = 0; c < 3; ++c) path.weight[c] = static_cast<float>(weight[c]);
                    if (path.kind == ColourPath::M) {
                        // Along the cylinder's surface, z unwrapped (gather.h).
                        const double dz = exitPoint.z + periodShift * period - entryZ;
                        const double dpsi =
                            std::remainder(std::atan2(exitPoint.y, exitPoint.x) - psi, kTwoPi);
                        const size_t bin =
                            static_cast<size_t>(exitDistanceBin(std::hypot(dz, dpsi))) * 3;
                        const size_t slot =
                            (offsetCell * kExitOffsetSlots + exitOffsetSlot(dz, dpsi)) * 3;
                        // wo in the exit frame: the entry frame turned by dpsi
                        // about the axis (an axial exit, without a point on
                        // the side, keeps the entry frame).
                        const double psiExit = std::isfinite(exitPoint.z) ? psi + dpsi : psi;
                        const Frame exit =
                            yarnFrame(t, Vec3{std::cos(psiExit), std::sin(psiExit), 0.0});
                        const size_t cellExit =
                            (binIn * nOut + bins.outgoingBin(exit.toLocal(dir))) * 3;
                        // The weight for the gather's own colour (any colour: W0 C_TT^k,
                        // as addColourPath gives the RDM).
                        for (int c = 0; c < 3; ++c) {
                            const int64_t w = GatherSums::toFixed(
                                o.anyColour ? path.weightFor(o.fiber.cTT, c) : weight[c]);
                            atomicAdd(sums.sumExitDistance[bin + c], w);
                            atomicAdd(sums.sumExitOffset[slot + c], w);
                            atomicAdd(sums.sumMExit[cellExit + c], w);
                        }
                    }
                    if (!o.anyColour) {
                        addPathWeight(sums, path.kind, binIn,
                                      static_cast<size_t>(std::max(path.outgoingBin, 0)), weight,
                                      atomicAdd);
                        continue;
                    }
                    if (weight.isBlack()) continue;
                    addColourPath(sums, path, o.fiber.cTT, atomicAdd);
                    chunkColourPaths[chunk].push_back(path);
                }
                rays += chunkRays;
                axial += chunkAxial;
                depthSum += chunkDepth;
                progress.add(static_cast<uint64_t>(last - first));
            }
        });
    });
    progress.finish();
    const auto now = std::chrono::steady_clock::now();
    sums.walkSeconds = std::chrono::duration<double>(now - walkStart).count();
    sums.seconds = std::chrono::duration<double>(now - start).count();
    sums.rays = rays.load();
    sums.axialPaths = axial.load();
    sums.depthSum = depthSum.load();
    sums.threads = threads;
    size_t recorded = 0;
    for (const auto& c : chunkColourPaths) recorded += c.size();
    sums.colourPaths.reserve(recorded);
    for (auto& c : chunkColourPaths) {
        sums.colourPaths.insert(sums.colourPaths.end(), c.begin(), c.end());
        std::vector<ColourPath>().swap(c);
    }
    return sums;
}

GatherResult normaliseGather(GatherSums sums, const GatherOptions& o, int64_t shards) {
    const auto start = std::chrono::steady_clock::now();
    const RdmBins& bins = sums.bins;
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    if (sums.firstPath != 0 || sums.endPath != o.paths || sums.count.size() != nIn ||
        sums.depth.size() != static_cast<size_t>(o.maxDepth) + 2)
        throw std::logic_error("normaliseGather: the sums are not those of the whole gather");
    GatherResult r;
    r.bins = bins;
    r.fiberRadius = sums.fiberRadius;
    r.plyLines = sums.plyLines;
    r.pT.assign(nIn, 0.0);
    r.truncated.assign(nIn * 3, 0.0);
    r.rdmR.assign(sums.sumR.size(), 0.0f);
    r.rdmM.assign(sums.sumM.size(), 0.0f);
    r.rdmMExit.assign(sums.sumMExit.size(), 0.0f);
    double truncatedTotal[3] = {0, 0, 0};
    for (size_t i = 0; i < nIn; ++i) {
        const int64_t count = sums.count[i];
        if (count == 0) continue;
        r.pT[i] = static_cast<double>(sums.countT[i]) / count;
        for (int c = 0; c < 3; ++c) {
            truncatedTotal[c] += sums.sumTruncated[i * 3 + c] / kFixedScale;
            r.truncated[i * 3 + c] = sums.sumTruncated[i * 3 + c] / kFixedScale / count;
        }
        for (size_t j = 0; j < nOut; ++j) {
            const double norm = 1.0 / (kFixedScale * count * bins.outgoingSolidAngle(j));
            for (int c = 0; c < 3; ++c) {
                const size_t cell = (i * nOut + j) * 3 + c;
                r.rdmR[cell] = static_cast<float>(sums.sumR[cell] * norm);
                r.rdmM[cell] = static_cast<float>(sums.sumM[cell] * norm);
                if (!r.rdmMExit.empty())
                    r.rdmMExit[cell] = static_cast<float>(sums.sumMExit[cell] * norm);
            }
        }
    }
    r.count = sums.count;
    r.countT = sums.countT;
    r.depth = sums.depth;
    r.exitDistance.resize(sums.sumExitDistance.size());
    for (size_t k = 0; k < r.exitDistance.size(); ++k)
        r.exitDistance[k] = sums.sumExitDistance[k] / kFixedScale / o.paths;
    r.exitOffset.resize(sums.sumExitOffset.size());
    for (size_t k = 0; k < r.exitOffset.size(); ++k)
        r.exitOffset[k] = sums.sumExitOffset[k] / kFixedScale / o.paths;
    r.colourPaths = std::move(sums.colourPaths);

    GatherStats& st = r.stats;
    st.paths = o.paths;
    st.rays = sums.rays;
    st.truncatedPaths = r.depth[o.maxDepth + 1];
    st.axialPaths = sums.axialPaths;
    st.meanDepth = static_cast<double>(sums.depthSum) / o.paths;
    for (int c = 0; c < 3; ++c) st.truncatedEnergy[c] = truncatedTotal[c] / o.paths;
    st.seconds = sums.seconds +
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    st.walkSeconds = sums.walkSeconds;
    st.threads = sums.threads;
    st.shards = shards;
    st.period = sums.period;
    st.fiberRadius = sums.fiberRadius;
    st.segments = sums.segments;
    st.embreeBytes = sums.embreeBytes;
    return r;
}

GatherResult gatherRdm(const GatherOptions& o) {
    if (!o.shard.whole())
        throw std::logic_error("gatherRdm: a shard has no RDM of its own (gather_merge.h)");
    return normaliseGather(gatherSums(o), o);
}

void writeGather(const GatherResult& r, const GatherOptions& o, TempDirCommit& out,
                 const nlohmann::json& extraMeta, GatherFiles files) {
    if (files == GatherFiles::Records && !o.anyColour)
        throw std::logic_error("writeGather: only an any-colour gather has records of its own");
    const bool all = files == GatherFiles::All;
    const auto file = [&](const char* name) {
        return (std::filesystem::path(out.path()) / name).string();
    };
    const RdmBins& b = r.bins;
    const size_t ti = b.thetaI, pi = b.phiI, to = b.thetaO, po = b.phiO;
    writeNpy(file("count.npy"), r.count.data(), {ti, pi});
    writeNpy(file("count_t.npy"), r.countT.data(), {ti, pi});
    writeNpy(file("p_t.npy"), r.pT.data(), {ti, pi});
    if (all) {
        writeNpy(file("rdm_r.npy"), r.rdmR.data(), {ti, pi, to, po, 3});
        writeNpy(file("rdm_m.npy"), r.rdmM.data(), {ti, pi, to, po, 3});
    }
    writeNpy(file("truncated.npy"), r.truncated.data(), {ti, pi, 3});
    writeNpy(file("depth.npy"), r.depth.data(), {r.depth.size()});
    if (!r.exitDistance.empty())
        writeNpy(file("exit_distance.npy"), r.exitDistance.data(),
                 {static_cast<size_t>(kExitDistanceBins) + 1, 3});
    // 6 MB: not in each node of a family's records-only gathers.
    if (all && !r.exitOffset.empty())
        writeNpy(file("exit_offset.npy"), r.exitOffset.data(), exitOffsetShape());
    if (all && !r.rdmMExit.empty())
        writeNpy(file("rdm_m_exit.npy"), r.rdmMExit.data(), {ti, pi, to, po, 3});
    if (all) writePlyLines(file("ply.txt"), r.plyLines, r.fiberRadius);
    if (o.anyColour) writeColourPaths(out.path(), r.colourPaths);
    nlohmann::json meta = gatherMetadata(r, o);
    meta.update(extraMeta);
    if (!all) meta["files"] = kGatherRecordsOnly;
    writeFileAtomic(file("meta.json"), meta.dump(2) + "\n");
    out.commit();
}

std::string formatPlyLines(const std::vector<std::vector<Vec3>>& lines, double fiberRadius,
                           const std::string& path) {
    CurveSet set;
    for (const std::vector<Vec3>& line : lines) {
        Curve& fiber = set.curves.emplace_back();
        fiber.points = line;
        fiber.radii.assign(line.size(), fiberRadius);
    }
    return formatCurveText(set, path);
}

void writePlyLines(const std::string& path, const std::vector<std::vector<Vec3>>& lines,
                   double fiberRadius) {
    writeFileAtomic(path, formatPlyLines(lines, fiberRadius, path));
}

nlohmann::json gatherInputs(const GatherOptions& o, double fiberRadius, double period,
                           int64_t segments) {
    const RdmBins& b = o.bins;
    return {{"material", o.material},
            {"fiber", o.fiber.toJson()},
            {"ply",
             {{"fibers", o.ply.fibers},
              {"density", o.ply.density},
              {"twist", o.ply.twist},
              {"radius", 1.0},
              {"fiber_radius", fiberRadius},
              {"period", period},
              {"segments_per_twist", o.ply.twist > 0 ? o.segmentsPerTwist : 1},
              {"segments", segments},
              {"primitive", "embree round linear curves, periodic in z"}}},
            {"bins", {b.thetaI, b.phiI, b.thetaO, b.phiO}},
            {"paths", o.paths},
            {"seed", o.seed},
            {"ply_seed", o.placementSeed()},
            {"max_depth", o.maxDepth},
            {"any_colour", o.anyColour},
            {"versions", {{"weft", WEFT_VERSION}, {"embree", EmbreeDevice::version()}}}};
}

GatherOptions gatherOptionsFromJson(const nlohmann::json& meta, const std::string& metaPath) {
    const JsonObjectReader r(meta, metaPath);
    GatherOptions o;
    o.material = r.string("material");
    o.fiber = FiberParams::fromJson(r.value("fiber"), metaPath, "fiber");
    const JsonObjectReader ply = r.object("ply");
    o.ply.fibers = static_cast<int>(ply.integer("fibers", {1, INT_MAX}));
    o.ply.density = ply.number("density");
    o.ply.twist = ply.number("twist");
    // A straight ply is one segment whatever the option was (gatherInputs).
    const int64_t segments = ply.integer("segments_per_twist", {1, INT_MAX});
    if (o.ply.twist > 0) o.segmentsPerTwist = static_cast<int>(segments);
    const std::vector<int64_t> bins = r.integers("bins", 4, 4, {1, 4096}, "(TI, PI, TO, PO)");
    o.bins = {static_cast<int>(bins[0]), static_cast<int>(bins[1]), static_cast<int>(bins[2]),
              static_cast<int>(bins[3])};
    o.paths = r.integer("paths", {1, kMaxPaths});
    o.seed = r.unsignedInteger("seed");
    o.plySeed = r.unsignedInteger("ply_seed");
    o.maxDepth = static_cast<int>(r.integer("max_depth", {1, 1000000}));
    // Gathers written before any-colour gathers existed have no such field.
    o.anyColour = meta.contains("any_colour") && r.boolean("any_colour");
    o.quiet = true;
    try {
        o.validate();
    } catch (const InputError& e) {
        throw InputError(metaPath + ": " + e.what());
    }
    return o;
}

std::vector<size_t> exitOffsetShape() {
    return {kExitOffsetTheta, kExitOffsetPhi, kExitOffsetSlots, 3};
}

ExitOffsetSummary summarizeExitOffset(const std::vector<double>& histogram, int thetaBand,
                                      int channel) {
    ExitOffsetSummary e;
    if (histogram.size() != kExitOffsetCells * kExitOffsetSlots * 3) return e;
    double inRange = 0, beyond = 0, sz = 0, sp = 0, szz = 0, spp = 0, szp = 0;
    for (int b = 0; b < kExitOffsetPhi; ++b) {
        const size_t cell = static_cast<size_t>(thetaBand) * kExitOffsetPhi + b;
        const auto weight = [&](size_t slot) {
            return histogram[(cell * kExitOffsetSlots + slot) * 3 + channel];
        };
        beyond += weight(kExitOffsetSlots - 1);
        for (int i = 0; i < kExitOffsetAxialBins; ++i)
            for (int j = 0; j < kExitOffsetAroundBins; ++j) {
                const double w = weight(static_cast<size_t>(i) * kExitOffsetAroundBins + j);
                if (w == 0) continue;
                const double z = (i + 0.5 - 0.5 * kExitOffsetAxialBins) * kExitOffsetAxialWidth;
                const double p = -kPi + (j + 0.5) * kTwoPi / kExitOffsetAroundBins;
                inRange += w;
                sz += w * z, sp += w * p, szz += w * z * z, spp += w * p * p, szp += w * z * p;
            }
    }
    e.weight = inRange + beyond;
    if (e.weight <= 0) return e;
    e.beyondFraction = beyond / e.weight;
    if (inRange <= 0) return e;
    e.meanAxial = sz / inRange;
    e.meanAround = sp / inRange;
    const double vz = std::max(0.0, szz / inRange - sqr(e.meanAxial)),
                 vp = std::max(0.0, spp / inRange - sqr(e.meanAround));
    e.sdAxial = std::sqrt(vz);
    e.sdAround = std::sqrt(vp);
    if (vz > 0 && vp > 0)
        e.correlation = (szp / inRange - e.meanAxial * e.meanAround) / (e.sdAxial * e.sdAround);
    return e;
}

ExitDistanceSummary summarizeExitDistance(const std::vector<double>& histogram, int channel) {
    ExitDistanceSummary e;
    if (histogram.size() != static_cast<size_t>(kExitDistanceBins + 1) * 3) return e;
    const auto weight = [&](int bin) { return histogram[static_cast<size_t>(bin) * 3 + channel]; };
    double inRange = 0, moment = 0;
    for (int b = 0; b < kExitDistanceBins; ++b) {
        inRange += weight(b);
        moment += weight(b) * (b + 0.5) * kExitDistanceBinWidth;
    }
    e.weight = inRange + weight(kExitDistanceBins);
    if (e.weight <= 0) return e;
    e.mean = inRange > 0 ? moment / inRange : 0.0;
    e.beyondFraction = weight(kExitDistanceBins) / e.weight;
    // Quantiles linear within a bin; one in the last bin is its lower edge.
    const auto quantile = [&](double q) {
        double below = 0;
        for (int b = 0; b <= kExitDistanceBins; ++b) {
            const double w = weight(b);
            if (below + w >= q * e.weight && w > 0) {
                if (b == kExitDistanceBins) return b * kExitDistanceBinWidth;
                return (b + (q * e.weight - below) / w) * kExitDistanceBinWidth;
            }
            below += w;
        }
        return kExitDistanceBins * kExitDistanceBinWidth;
    };
    e.median = quantile(0.5);
    e.p90 = quantile(0.9);
    return e;
}

nlohmann::json gatherMetadata(const GatherResult& r, const GatherOptions& o) {
    const GatherStats& s = r.stats;
    nlohmann::json meta = gatherInputs(o, s.fiberRadius, s.period, s.segments);
    meta.update({
        {"format", "weft-gather"},
        {"version", 1},
        {"threads", s.threads},
        {"shards", s.shards},
        {"elapsed_seconds", s.seconds},
        {"paths_per_second", s.paths / s.seconds},
        {"rays", s.rays},
        {"walk_seconds", s.walkSeconds},
        {"rays_per_second", s.rays / s.walkSeconds},
        {"mean_depth", s.meanDepth},
        {"truncated_fraction", static_cast<double>(s.truncatedPaths) / s.paths},
        {"truncated_energy", {s.truncatedEnergy[0], s.truncatedEnergy[1], s.truncatedEnergy[2]}},
        {"end_exit_fraction", 0.0},
        {"axial_fraction", static_cast<double>(s.axialPaths) / s.paths},
        {"embree_bytes", s.embreeBytes},
        {"arrays",
         {{"count", "int64 (TI,PI): paths per incident bin"},
          {"count_t", "int64 (TI,PI): T paths (no fiber interaction) per incident bin"},
          {"p_t", "float64 (TI,PI): count_t / count (0 where count is 0)"},
          {"rdm_r", "float32 (TI,PI,TO,PO,3): R weight / count / outgoing solid angle"},
          {"rdm_m", "float32 (TI,PI,TO,PO,3): M weight / count / outgoing solid angle"},
          {"truncated", "float64 (TI,PI,3): weight of paths cut at max_depth / count"},
          {"depth",
           "int64 (max_depth+2): paths by number of fiber interactions; last: truncated"}}}});
    if (!r.rdmMExit.empty())
        meta["arrays"]["rdm_m_exit"] =
            "float32 (TI,PI,TO,PO,3): rdm_m with wo in the exit frame, the yarn frame where "
            "the path left the ply (gather.h)";
    if (!r.exitDistance.empty()) {
        meta["arrays"]["exit_distance"] =
            "float64 (" + std::to_string(kExitDistanceBins + 1) +
            ",3): M weight per path by the distance from entry to exit along the cylinder, "
            "bins of 0.125 ply radii; last: farther (gather.h)";
        nlohmann::json exit = {{"unit", "ply radii, along the bounding cylinder"},
                               {"bin_width", kExitDistanceBinWidth},
                               {"bins", kExitDistanceBins}};
        for (int c = 0; c < 3; ++c) {
            const ExitDistanceSummary e = summarizeExitDistance(r.exitDistance, c);
            exit["m_weight"].push_back(e.weight);
            exit["mean"].push_back(e.mean);
            exit["median"].push_back(e.median);
            exit["p90"].push_back(e.p90);
            exit["beyond_fraction"].push_back(e.beyondFraction);
        }
        meta["exit_distance"] = exit;
    }
    if (!r.exitOffset.empty()) {
        meta["arrays"]["exit_offset"] =
            "float64 (" + std::to_string(kExitOffsetTheta) + "," + std::to_string(kExitOffsetPhi) +
            "," + std::to_string(kExitOffsetSlots) +
            ",3): M weight per path by signed exit offset (dz, dpsi) per incident cell "
            "(theta_i band, phi_i band); last slot: beyond the axial range (gather.h)";
        nlohmann::json offset = {
            {"unit", "ply radii along the axis (dz), radians around it (dpsi)"},
            {"axial_bins", kExitOffsetAxialBins},
            {"axial_bin_width", kExitOffsetAxialWidth},
            {"around_bins", kExitOffsetAroundBins},
            {"theta_bands", kExitOffsetTheta},
            {"phi_bands", kExitOffsetPhi}};
        for (int a = 0; a < kExitOffsetTheta; ++a) {
            nlohmann::json band;
            for (int c = 0; c < 3; ++c) {
                const ExitOffsetSummary e = summarizeExitOffset(r.exitOffset, a, c);
                band["m_weight"].push_back(e.weight);
                band["beyond_fraction"].push_back(e.beyondFraction);
                band["mean_dz"].push_back(e.meanAxial);
                band["mean_dpsi"].push_back(e.meanAround);
                band["sd_dz"].push_back(e.sdAxial);
                band["sd_dpsi"].push_back(e.sdAround);
                band["correlation"].push_back(e.correlation);
            }
            offset["theta_bands_summary"].push_back(band);
        }
        meta["exit_offset"] = offset;
    }
    if (o.anyColour) {
        meta["colour_paths"] = static_cast<int64_t>(r.colourPaths.size());
        meta["lobe_choice"] =
            "as for C_TT = 1, each event weighted by its lobe: R F/p_R, TT (1-F) C_TT/(1-p_R)";
        meta["arrays"].update(colourPathArrayDescriptions());
    }
    return meta;
}

}  // namespace weft
