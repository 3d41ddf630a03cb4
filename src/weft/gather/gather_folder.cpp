#include "weft/gather/gather_folder.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>
#include <utility>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"
#include "weft/core/npy.h"

namespace weft {

namespace {

// The shards of one gather, field by field (docs/cluster.md).
constexpr std::string_view kSharedPartFields[] = {
    "material",     "fiber",        "ply.fibers",
    "ply.density",  "ply.twist",    "ply.radius",
    "ply.fiber_radius", "ply.period", "ply.segments_per_twist",
    "ply.segments", "ply.primitive", "bins",
    "paths",        "seed",         "ply_seed",
    "max_depth",    "any_colour",   "shard.count",
    "versions.weft"};

// `field` of the "ply" object must be `expected` (within rounding of the
// last digit of a hand-written file): what the ply's other fields give.
void expectPlyNumber(const JsonObjectReader& ply, std::string_view field, double expected,
                     const std::string& formula) {
    const double v = ply.number(field);
    if (!std::isfinite(expected) || !(std::abs(v - expected) <= 1e-12 * expected))
        ply.failOutOfRange(field, formatNumber(v), formatNumber(expected) + " (" + formula + ")");
}

// meta.json's "ply" against the options: radius 1 (gathers are scale-free),
// fiber radius and period from the ply's fields, a segment count that holds a
// segment per fiber. The exact ply is checkTracedPly's business.
void checkPlyDescription(const JsonObjectReader& r, const GatherOptions& o) {
    const JsonObjectReader ply = r.object("ply");
    expectPlyNumber(ply, "radius", 1.0, "a gather's ply has radius R = 1");
    expectPlyNumber(ply, "fiber_radius", std::sqrt(o.ply.density / o.ply.fibers),
                    "R sqrt(density / fibers)");
    if (o.ply.twist > 0)
        expectPlyNumber(ply, "period", 2.0 / o.ply.twist, "2R / twist");
    else
        expectPlyNumber(ply, "period", 4.0, "4R for a straight ply");
    ply.integer("segments", {o.ply.fibers, int64_t{1} << 53, "(at least one per fiber)"});
    if (o.ply.twist == 0)
        ply.integer("segments_per_twist", {1, 1, "(a straight ply is one segment per fiber)"});
    ply.string("primitive");
}

}  // namespace

std::string GatherFolder::file(std::string_view name) const {
    return (std::filesystem::path(dir) / name).string();
}

int64_t GatherFolder::paths() const {
    return options.shard.end(options.paths) - options.shard.begin(options.paths);
}

bool GatherFolder::recordsOnly() const {
    return meta.is_object() && meta.contains("files") && meta.at("files") == kGatherRecordsOnly;
}

std::vector<std::string> GatherFolder::files() const {
    std::vector<const char*> names = {"meta.json", "count.npy", "count_t.npy", "depth.npy",
                                      "ply.txt"};
    if (kind == GatherFolderKind::Gather)
        names.insert(names.end(), {"p_t.npy", "rdm_r.npy", "rdm_m.npy", "truncated.npy",
                                   "exit_distance.npy", "exit_offset.npy", "rdm_m_exit.npy"});
    else
        names.insert(names.end(),
                     {"sum_r.npy", "sum_m.npy", "sum_truncated.npy", "sum_exit_distance.npy",
                      "sum_exit_offset.npy", "sum_m_exit.npy"});
    if (options.anyColour)
        names.insert(names.end(), {"paths_bins.npy", "paths_kind.npy", "paths_weight.npy"});
    std::vector<std::string> paths;
    for (const char* name : names) paths.push_back(file(name));
    return paths;
}

void checkGatherMeta(const nlohmann::json& meta, const std::string& metaPath) {
    if (meta.is_object() && meta.contains("format") && meta.at("format") == kGatherPartFormat)
        throw InputError(metaPath +
                         ": one shard of a gather (\"format\" is \"weft-gather-part\"): merge "
                         "all its shards with `weft gather merge PART... --out DIR` first");
    if (!meta.is_object() || meta.value("format", "") != "weft-gather")
        throw InputError(metaPath + ": not a weft gather (\"format\" must be \"weft-gather\")");
    if (meta.value("version", 0) != 1)
        throw InputError(metaPath + ": unsupported version " +
                         meta.value("version", nlohmann::json()).dump() + " (supported: 1)");
}

GatherFolder readGatherFolder(const std::string& dir, GatherFolderKind kind) {
    GatherFolder f;
    f.kind = kind;
    f.dir = dir;
    f.metaPath = f.file("meta.json");
    f.meta = readJsonFile(f.metaPath);
    const JsonObjectReader r(f.meta, f.metaPath);
    if (kind == GatherFolderKind::Gather) {
        checkGatherMeta(f.meta, f.metaPath);
    } else {
        const std::string format = r.string("format");
        if (format == "weft-gather")
            throw InputError(f.metaPath +
                             ": a whole gather, not a shard of one (\"format\" is "
                             "\"weft-gather\"): merge the directories that weft gather "
                             "--shard K/N wrote");
        if (format != kGatherPartFormat)
            throw InputError(f.metaPath + ": not a gather shard (\"format\" is \"" + format +
                             "\", expected \"" + kGatherPartFormat + "\")");
        r.integer("version", {1, 1, "(the part format this weft reads)"});
    }
    GatherOptions& o = f.options;
    o = gatherOptionsFromJson(f.meta, f.metaPath);
    checkPlyDescription(r, o);
    if (kind == GatherFolderKind::Gather) return f;

    // A part: its shard, and what every part writes.
    const JsonObjectReader shard = r.object("shard");
    o.shard.count = shard.integer("count", {1, Shard::kMaxCount});
    o.shard.index = shard.integer("index", {0, o.shard.count - 1});
    try {
        o.validate();
    } catch (const InputError& e) {
        throw InputError(f.metaPath + ": " + e.what());
    }
    const int64_t first = shard.integer("first_path", {0, kMaxPaths});
    const int64_t end = shard.integer("end_path", {0, kMaxPaths});
    if (first != o.shard.begin(o.paths) || end != o.shard.end(o.paths))
        throw InputError(f.metaPath + ": shard " + o.shard.toString() + " of " +
                         std::to_string(o.paths) + " paths covers [" +
                         std::to_string(o.shard.begin(o.paths)) + ", " +
                         std::to_string(o.shard.end(o.paths)) + "), but \"shard\" says [" +
                         std::to_string(first) + ", " + std::to_string(end) + ")");
    // Parts have always said whether they record paths: a missing flag is damage.
    r.boolean("any_colour");
    r.object("versions").string("weft");
    const int64_t paths = f.paths();
    r.integer("rays", {0, std::numeric_limits<int64_t>::max() / 65536});
    r.integer("axial_paths", {0, paths});
    r.integer("depth_sum", {0, paths * o.maxDepth});
    r.number("elapsed_seconds", NumberRange::atLeast(0));
    r.number("walk_seconds", NumberRange::atLeast(0));
    r.integer("threads", {1, 1024});
    return f;
}

std::span<const std::string_view> sharedPartFields() { return kSharedPartFields; }

nlohmann::json jsonAtPath(const nlohmann::json& meta, std::string_view path) {
    const nlohmann::json* v = &meta;
    while (!path.empty()) {
        const size_t dot = path.find('.');
        const std::string key(path.substr(0, dot));
        if (!v->is_object() || !v->contains(key)) return nullptr;
        v = &v->at(key);
        path = dot == std::string_view::npos ? std::string_view() : path.substr(dot + 1);
    }
    return *v;
}

void checkTracedPly(const GatherFolder& f, const GatherSums& traced) {
    const nlohmann::json expected =
        gatherInputs(f.options, traced.fiberRadius, traced.period, traced.segments).at("ply");
    for (const auto& [key, value] : expected.items()) {
        const nlohmann::json have = jsonAtPath(f.meta, "ply." + key);
        if (have != value)
            throw InputError(f.metaPath + ": \"ply." + key + "\" is " + have.dump() +
                             ", but the ply that its fiber, ply and seed fields give has " +
                             value.dump() + ": it was not traced on that ply");
    }
    const std::string plyPath = f.file("ply.txt");
    // A gather of records keeps no ply.txt: the lines traced from its fields
    // are the ply, and a recolouring writes them.
    if (f.recordsOnly()) return;
    const std::string have = readFile(plyPath);
    const std::string want = formatPlyLines(traced.plyLines, traced.fiberRadius, plyPath);
    if (have == want) return;
    const auto diff = std::mismatch(have.begin(), have.end(), want.begin(), want.end());
    const size_t line = 1 + static_cast<size_t>(std::count(have.begin(), diff.first, '\n'));
    throw InputError(plyPath + ": line " + std::to_string(line) +
                     " differs from the ply that meta.json's fiber, ply and seed fields give "
                     "(every shard and gather of these options traces the same fibers)");
}

void checkDistinctFiles(const std::vector<std::string>& paths) {
    std::map<std::pair<dev_t, ino_t>, const std::string*> seen;
    for (const std::string& p : paths) {
        struct stat st {};
        if (::stat(p.c_str(), &st) != 0) continue;
        const auto [it, added] = seen.emplace(std::make_pair(st.st_dev, st.st_ino), &p);
        if (!added)
            throw InputError(p + " and " + *it->second + " are one file (device " +
                             std::to_string(st.st_dev) + ", inode " +
                             std::to_string(st.st_ino) +
                             ": a symbolic or hard link): every file of a gather, and of each "
                             "part of a merge, must be its own");
    }
}

std::string gatherElementName(size_t k, const std::vector<size_t>& shape) {
    std::string s = "element " + std::to_string(k);
    if (shape.size() < 2) return s;
    std::vector<size_t> index(shape.size());
    size_t rest = k;
    for (size_t d = shape.size(); d-- > 0;) {
        index[d] = shape[d] ? rest % shape[d] : 0;
        rest = shape[d] ? rest / shape[d] : 0;
    }
    s += " (";
    for (size_t d = 0; d < index.size(); ++d) s += (d ? ", " : "") + std::to_string(index[d]);
    return s + ")";
}

template <typename T>
std::vector<T> readGatherArray(const std::string& path, const char* descr,
                               const std::vector<size_t>& shape, const ArrayRange& range) {
    const NpyArray a = readNpy(path);
    if (a.descr != descr || a.shape != shape)
        throw InputError(path + ": expected " + descr + " of shape " + npyShapeString(shape) +
                         ", got " + a.descr + " " + npyShapeString(a.shape));
    std::vector<T> values(a.size());
    if (!values.empty()) std::memcpy(values.data(), a.bytes.data(), values.size() * sizeof(T));
    for (size_t k = 0; k < values.size(); ++k) {
        const double v = static_cast<double>(values[k]);
        if (std::isfinite(v) && v >= range.lo && v <= range.hi) continue;
        const std::string value = std::is_integral_v<T> ? std::to_string(values[k])
                                                        : formatNumber(v);
        const std::string allowed =
            std::isinf(range.hi) ? "a finite number >= " + formatNumber(range.lo)
                                 : "a finite number in [" + formatNumber(range.lo) + ", " +
                                       formatNumber(range.hi) + "]";
        throw InputError(path + ": " + gatherElementName(k, shape) + " is " + value +
                         " (allowed: " + allowed + range.note + ")");
    }
    return values;
}

template std::vector<int64_t> readGatherArray(const std::string&, const char*,
                                              const std::vector<size_t>&, const ArrayRange&);
template std::vector<double> readGatherArray(const std::string&, const char*,
                                             const std::vector<size_t>&, const ArrayRange&);
template std::vector<float> readGatherArray(const std::string&, const char*,
                                            const std::vector<size_t>&, const ArrayRange&);

GatherCounts readGatherCounts(const GatherFolder& f) {
    const GatherOptions& o = f.options;
    const int64_t paths = f.paths();
    const std::vector<size_t> incident = {static_cast<size_t>(o.bins.thetaI),
                                          static_cast<size_t>(o.bins.phiI)};
    const ArrayRange perBin{0, static_cast<double>(paths),
                            f.kind == GatherFolderKind::Part ? " (the part's paths)"
                                                             : " (the gather's paths)"};
    GatherCounts c;
    const std::string countPath = f.file("count.npy"), countTPath = f.file("count_t.npy"),
                      depthPath = f.file("depth.npy");
    c.count = readGatherArray<int64_t>(countPath, "<i8", incident, perBin);
    c.countT = readGatherArray<int64_t>(countTPath, "<i8", incident, perBin);
    c.depth = readGatherArray<int64_t>(depthPath, "<i8", {static_cast<size_t>(o.maxDepth) + 2},
                                       perBin);
    // Each element is at most `paths` (<= 2^31): no sum below overflows.
    const auto sum = [](const std::vector<int64_t>& v) {
        return std::accumulate(v.begin(), v.end(), int64_t{0});
    };
    const std::string pathsText =
        std::to_string(paths) + (f.kind == GatherFolderKind::Part
                                     ? " paths of shard " + o.shard.toString() + " in meta.json"
                                     : " paths of meta.json's \"paths\"");
    for (const auto& [path, values] : {std::pair{&countPath, &c.count}, {&depthPath, &c.depth}})
        if (sum(*values) != paths)
            throw InputError(*path + ": the elements sum to " + std::to_string(sum(*values)) +
                             ", but must sum to the " + pathsText);
    for (size_t i = 0; i < c.count.size(); ++i)
        if (c.countT[i] > c.count[i])
            throw InputError(countTPath + ": " + gatherElementName(i, incident) + " is " +
                             std::to_string(c.countT[i]) + ", more than the " +
                             std::to_string(c.count[i]) +
                             " paths of that incident bin in count.npy (T paths are some of "
                             "them)");
    if (c.depth[0] != sum(c.countT))
        throw InputError(depthPath + ": element 0 (paths that met no fiber) is " +
                         std::to_string(c.depth[0]) + ", but count_t.npy holds " +
                         std::to_string(sum(c.countT)) + " T paths (they must be equal)");
    if (f.kind == GatherFolderKind::Part) {
        // The walks' interactions, a truncated path counting max_depth (gather.cpp).
        int64_t depthSum = 0;
        for (int d = 1; d <= o.maxDepth + 1; ++d)
            depthSum += static_cast<int64_t>(std::min(d, o.maxDepth)) * c.depth[d];
        const int64_t said = f.meta.at("depth_sum").get<int64_t>();
        if (said != depthSum)
            throw InputError(f.metaPath + ": \"depth_sum\" is " + std::to_string(said) +
                             ", but depth.npy gives " + std::to_string(depthSum) +
                             " fiber interactions (they must be equal)");
    }
    return c;
}

}  // namespace weft
