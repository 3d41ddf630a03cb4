// weft/gather/rdm_io.h — reading a gather directory back (weft fit, weft yarn check,
// weft rdm slice, Python).
//
// loadRdm(DIR) reads meta.json, count.npy, p_t.npy, rdm_r.npy and rdm_m.npy
// as written by `weft gather`, and checks every file of the gather through
// gather_folder.h: meta.json's fields, the counts against each other
// (count_t.npy and depth.npy too), p_t = count_t / count, every map finite
// and >= 0, truncated.npy, exit_distance.npy and exit_offset.npy, no file a
// link to another.
// Any mismatch is an InputError naming the file and what was expected.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/gather/gather_folder.h"
#include "weft/gather/rdm.h"

namespace weft {

struct RdmData {
    std::string dir;
    nlohmann::json meta;
    RdmBins bins;
    std::vector<int64_t> count;     // (TI, PI)
    std::vector<double> pT;         // (TI, PI)
    std::vector<float> rdmR, rdmM;  // (TI, PI, TO, PO, 3)
    // exit_offset.npy (gather.h GatherResult::exitOffset); empty where the
    // gather has none (recoloured, or written before it was recorded).
    std::vector<double> exitOffset;
    // rdm_m_exit.npy (GatherResult::rdmMExit); empty where the gather has none.
    std::vector<float> rdmMExit;
};

RdmData loadRdm(const std::string& dir);

}  // namespace weft
