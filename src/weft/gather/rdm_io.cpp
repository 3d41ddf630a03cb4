#include "weft/gather/rdm_io.h"

#include <cmath>
#include <cstring>
#include <filesystem>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/npy.h"

namespace weft {

namespace {

template <typename T>
std::vector<T> readArray(const std::string& path, const std::string& descr,
                         const std::vector<size_t>& shape) {
    const NpyArray a = readNpy(path);
    if (a.descr != descr || a.shape != shape)
        throw InputError(path + ": expected " + descr + " of shape " + npyShapeString(shape) +
                         ", got " + a.descr + " " + npyShapeString(a.shape));
    std::vector<T> values(a.size());
    std::memcpy(values.data(), a.bytes.data(), values.size() * sizeof(T));
    for (size_t k = 0; k < values.size(); ++k) {
        if (!std::isfinite(static_cast<double>(values[k])) || values[k] < 0)
            throw InputError(path + ": element " + std::to_string(k) + " is " +
                             std::to_string(static_cast<double>(values[k])) +
                             " (must be finite and >= 0)");
    }
    return values;
}

}  // namespace

void checkGatherMeta(const nlohmann::json& meta, const std::string& metaPath) {
    if (meta.is_object() && meta.contains("format") && meta.at("format") == "weft-gather-part")
        throw InputError(metaPath +
                         ": one shard of a gather (\"format\" is \"weft-gather-part\"): merge "
                         "all its shards with `weft gather merge PART... --out DIR` first");
    if (!meta.is_object() || meta.value("format", "") != "weft-gather")
        throw InputError(metaPath + ": not a weft gather (\"format\" must be \"weft-gather\")");
    if (meta.value("version", 0) != 1)
        throw InputError(metaPath + ": unsupported version " +
                         meta.value("version", nlohmann::json()).dump() + " (supported: 1)");
}

RdmData loadRdm(const std::string& dir) {
    namespace fs = std::filesystem;
    RdmData d;
    d.dir = dir;
    const std::string metaPath = (fs::path(dir) / "meta.json").string();
    d.meta = readJsonFile(metaPath);
    checkGatherMeta(d.meta, metaPath);
    const auto& b = d.meta.contains("bins") ? d.meta.at("bins") : nlohmann::json();
    if (!b.is_array() || b.size() != 4 || !b[0].is_number_integer() || !b[1].is_number_integer() ||
        !b[2].is_number_integer() || !b[3].is_number_integer())
        throw InputError(metaPath + ": \"bins\" must be four integers [TI, PI, TO, PO]");
    // Through double: get<int> would wrap 2^32 + 22 around to 22.
    const auto count = [&](int k) {
        const double v = b[k].get<double>();
        return v >= 0 && v <= 1e9 ? static_cast<int>(v) : -1;  // -1: validate() names it
    };
    d.bins = {count(0), count(1), count(2), count(3)};
    try {
        d.bins.validate();
    } catch (const InputError& e) {
        throw InputError(metaPath + ": " + e.what());
    }
    const size_t ti = d.bins.thetaI, pi = d.bins.phiI, to = d.bins.thetaO, po = d.bins.phiO;
    const auto file = [&](const char* name) { return (fs::path(dir) / name).string(); };
    d.count = readArray<int64_t>(file("count.npy"), "<i8", {ti, pi});
    d.pT = readArray<double>(file("p_t.npy"), "<f8", {ti, pi});
    d.rdmR = readArray<float>(file("rdm_r.npy"), "<f4", {ti, pi, to, po, 3});
    d.rdmM = readArray<float>(file("rdm_m.npy"), "<f4", {ti, pi, to, po, 3});
    for (size_t i = 0; i < d.pT.size(); ++i)
        if (d.pT[i] > 1.0)
            throw InputError(file("p_t.npy") + ": element " + std::to_string(i) + " is " +
                             std::to_string(d.pT[i]) + " (a probability must be in [0, 1])");
    return d;
}

}  // namespace weft
