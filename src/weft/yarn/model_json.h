// weft/yarn/model_json.h — the JSON pieces that model.json (yarn_model.h) and
// a family model file (family_model.h) share: one reader and one writer of a
// network and of the sampling block, and the file's layout printer.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/json_reader.h"
#include "weft/yarn/network.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

// The network under `name` ("t_net") of the model object `model`: `inputs`
// inputs and `outputs` outputs (InputError naming the JSON path otherwise).
NetworkWeights readModelNetwork(const JsonObjectReader& model, const std::string& name, int inputs,
                                int outputs);
// {"layers": [...], "output": name}, every float written exactly.
nlohmann::json modelNetworkToJson(const NetworkWeights& net);
// The "sampling" block of `model`, each parameter in its range.
SamplingParams readModelSampling(const JsonObjectReader& model);
nlohmann::json modelSamplingToJson(const SamplingParams& sampling);
// The "c_tt" node colours of an energy calibration by colour `calibration`
// (1 to ColourCalibration::kMaxNodes numbers; their order is the caller's check).
std::vector<double> readCalibrationNodeColours(const JsonObjectReader& calibration);
// The file's text: keys in the layout order of docs/model-format.md, weight
// rows on one line, numbers in their shortest round-trip form.
std::string formatModelJson(const nlohmann::json& document);

}  // namespace weft
