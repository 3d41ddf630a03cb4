// weft/gather/rdm_io.h — reading a gather directory back (weft fit, weft yarn check).
//
// loadRdm(DIR) reads meta.json, count.npy, p_t.npy, rdm_r.npy and rdm_m.npy
// as written by `weft gather` and checks them against each other: format and
// version, the four bin counts, every array's dtype and shape, finite
// non-negative values. Any mismatch is an InputError naming the file and
// what was expected.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/gather/rdm.h"

namespace weft {

struct RdmData {
    std::string dir;
    nlohmann::json meta;
    RdmBins bins;
    std::vector<int64_t> count;     // (TI, PI)
    std::vector<double> pT;         // (TI, PI)
    std::vector<float> rdmR, rdmM;  // (TI, PI, TO, PO, 3)
};

RdmData loadRdm(const std::string& dir);

// InputError naming metaPath unless `meta` (a gather's meta.json) is a whole
// weft gather of format version 1; a shard of one is told to merge first.
void checkGatherMeta(const nlohmann::json& meta, const std::string& metaPath);

}  // namespace weft
