#include "weft/gather/rdm_io.h"

#include <cmath>
#include <filesystem>
#include <limits>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/npy.h"
#include "weft/gather/gather_folder.h"

namespace weft {

RdmData loadRdm(const std::string& dir) {
    const GatherFolder f = readGatherFolder(dir, GatherFolderKind::Gather);
    // Records for any C_TT only (a point of a family gather, gather/family.h).
    if (f.recordsOnly())
        throw InputError(dir +
                         " holds an any-colour gather's records only (a point of a family "
                         "gather), without the RDM arrays of one colour; weft gather recolour " +
                         dir + " --c-tt R,G,B --out DIR writes its gather of one colour");
    checkDistinctFiles(f.files());
    RdmData d;
    d.dir = dir;
    d.meta = f.meta;
    d.bins = f.options.bins;
    const GatherCounts counts = readGatherCounts(f);
    d.count = counts.count;
    const size_t ti = d.bins.thetaI, pi = d.bins.phiI, to = d.bins.thetaO, po = d.bins.phiO;
    constexpr double kInf = std::numeric_limits<double>::infinity();
    const ArrayRange weights{0, kInf, ""};
    d.pT = readGatherArray<double>(f.file("p_t.npy"), "<f8", {ti, pi}, {0, 1, " (a probability)"});
    for (size_t i = 0; i < d.pT.size(); ++i) {
        const double expected = d.count[i] > 0 ? static_cast<double>(counts.countT[i]) /
                                                     static_cast<double>(d.count[i])
                                               : 0.0;
        if (d.pT[i] != expected)
            throw InputError(f.file("p_t.npy") + ": " + gatherElementName(i, {ti, pi}) + " is " +
                             formatNumber(d.pT[i]) + ", but count_t.npy / count.npy is " +
                             formatNumber(expected) + " there (they must be equal)");
    }
    d.rdmR = readGatherArray<float>(f.file("rdm_r.npy"), "<f4", {ti, pi, to, po, 3}, weights);
    d.rdmM = readGatherArray<float>(f.file("rdm_m.npy"), "<f4", {ti, pi, to, po, 3}, weights);
    // Not used by the fit, but part of the gather: damage to them is damage to it.
    const std::string truncatedPath = f.file("truncated.npy");
    const std::vector<double> truncated =
        readGatherArray<double>(truncatedPath, "<f8", {ti, pi, 3}, weights);
    const bool anyTruncated = counts.depth.back() > 0;
    for (size_t k = 0; k < truncated.size(); ++k)
        if (truncated[k] != 0 && (!anyTruncated || d.count[k / 3] == 0))
            throw InputError(truncatedPath + ": " + gatherElementName(k, {ti, pi, 3}) + " is " +
                             formatNumber(truncated[k]) + ", but " +
                             (anyTruncated ? "count.npy has no paths in that incident bin"
                                           : "depth.npy records no truncated path") +
                             " (it must be 0)");
    // A recoloured gather has none.
    const std::string exitPath = f.file("exit_distance.npy");
    std::error_code ec;
    if (std::filesystem::exists(exitPath, ec))
        readGatherArray<double>(exitPath, "<f8", {static_cast<size_t>(kExitDistanceBins) + 1, 3},
                                weights);
    // Nor one written before the exit offsets were recorded (gather.h).
    const std::string offsetPath = f.file("exit_offset.npy");
    if (std::filesystem::exists(offsetPath, ec))
        d.exitOffset = readGatherArray<double>(offsetPath, "<f8", exitOffsetShape(), weights);
    const std::string exitFramePath = f.file("rdm_m_exit.npy");
    if (std::filesystem::exists(exitFramePath, ec))
        d.rdmMExit = readGatherArray<float>(exitFramePath, "<f4", {ti, pi, to, po, 3}, weights);
    return d;
}

}  // namespace weft
