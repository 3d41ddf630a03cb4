// The family model and its file (family_model.h).
#include "weft/yarn/family_model.h"

#include <cmath>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"
#include "weft/yarn/model_json.h"

namespace weft {

namespace {

using nlohmann::json;

constexpr const char* kMaskingForm = "symmetric-quadratic";
constexpr const char* kMaskingFeatures = "linear";
constexpr const char* kCalibrationForm = "log-polynomial-by-colour";
constexpr const char* kCalibrationFeatures = "linear-by-channel";
// The fiber colour of a yarn made by at(): the family gather's own (gather/family.h).
constexpr double kFamilyGatheredCTT = 0.5;

// A block of coefficients, row k = block[k * width, (k + 1) * width), as
// JSON rows (the masking's and the calibration's layout).
json coefficientRows(const std::vector<double>& block, size_t width) {
    json rows = json::array();
    for (size_t k = 0; k + width <= block.size(); k += width)
        rows.push_back(std::vector<double>(block.begin() + static_cast<std::ptrdiff_t>(k),
                                           block.begin() + static_cast<std::ptrdiff_t>(k + width)));
    return rows;
}

// `count` rows of `width` numbers at `path`, appended to *out; InputError
// naming the row or number otherwise.
void readCoefficientRows(const json& rows, const std::string& source, const std::string& path,
                         size_t count, size_t width, std::vector<double>* out) {
    const std::string shape =
        "expected " + std::to_string(count) + " rows of " + std::to_string(width) + " numbers";
    if (!rows.is_array() || rows.size() != count)
        throwJsonError(source, path, shape + ", got " + describeJson(rows));
    for (size_t k = 0; k < count; ++k) {
        if (!rows[k].is_array() || rows[k].size() != width)
            throwJsonError(source, jsonIndexPath(path, k),
                           shape + ", got " + describeJson(rows[k]));
        for (size_t l = 0; l < width; ++l)
            out->push_back(
                readJsonNumber(rows[k][l], source, jsonIndexPath(jsonIndexPath(path, k), l)));
    }
}

}  // namespace

std::array<double, kFamilyMaskingFeatures> familyMaskingFeatures(const FamilyBox& box,
                                                                 const YarnPoint& p) {
    const auto q = box.normalised(p);
    return {1.0, q[0], q[1], q[2], q[3], q[4], q[5]};
}

std::array<double, kFamilyCalibrationFeatures> familyCalibrationFeatures(const FamilyBox& box,
                                                                         const YarnPoint& p,
                                                                         int channel) {
    const auto q = box.normalised(p);
    return {1.0, q[0], q[1], q[2], q[3], q[4], q[5], q[6 + channel]};
}

void FamilyCalibration::validate(const std::string& what) const {
    if (empty()) return;
    if (degree > EnergyCalibration::kMaxDegree)
        throw InputError(what + ".degree: " + std::to_string(degree) + " is out of range [0, " +
                         std::to_string(EnergyCalibration::kMaxDegree) + "]");
    const size_t size =
        static_cast<size_t>(EnergyCalibration::termCount(degree)) * kFamilyCalibrationFeatures;
    auto checkBlock = [&](const std::vector<double>& block, const std::string& where) {
        if (block.size() != size)
            throw InputError(where + ": expected " +
                             std::to_string(EnergyCalibration::termCount(degree)) + " rows of " +
                             std::to_string(kFamilyCalibrationFeatures) + " coefficients");
        for (double v : block)
            if (!std::isfinite(v)) throw InputError(where + ": a coefficient is not finite");
    };
    checkBlock(r, what + ".r");
    if (m.size() != cTT.size() || cTT.empty() ||
        cTT.size() > static_cast<size_t>(ColourCalibration::kMaxNodes))
        throw InputError(what + ": expected one block of m rows per node colour, 1 to " +
                         std::to_string(ColourCalibration::kMaxNodes) + " of them, got " +
                         std::to_string(m.size()) + " for " + std::to_string(cTT.size()) +
                         " colours");
    for (size_t g = 0; g < m.size(); ++g) checkBlock(m[g], what + ".m[" + std::to_string(g) + "]");
    ColourCalibration::validateNodeColours(cTT, what);
}

ColourCalibration FamilyCalibration::at(const FamilyBox& box, const YarnPoint& p) const {
    ColourCalibration out;
    if (empty()) return out;
    const int terms = EnergyCalibration::termCount(degree);
    std::array<std::array<double, kFamilyCalibrationFeatures>, 3> f;
    for (int c = 0; c < 3; ++c) f[c] = familyCalibrationFeatures(box, p, c);
    auto rows = [&](const std::vector<double>& block, int c) {
        std::vector<double> coefficients(static_cast<size_t>(terms), 0.0);
        for (int k = 0; k < terms; ++k)
            for (int l = 0; l < kFamilyCalibrationFeatures; ++l)
                coefficients[k] += block[k * kFamilyCalibrationFeatures + l] * f[c][l];
        return coefficients;
    };
    out.cTT = cTT;
    for (const std::vector<double>& block : m) {
        EnergyCalibration node;
        node.degree = degree;
        for (int c = 0; c < 3; ++c) node.r[c] = rows(r, c), node.m[c] = rows(block, c);
        out.nodes.push_back(std::move(node));
    }
    return out;
}

YarnPoint FamilyModel::centre() const {
    return box.at({0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5});
}

void FamilyModel::validate() const {
    box.validate("box");
    tNet.validate("t_net", kFamilyTInputs, 1, OutputFunction::Sigmoid,
                  "P(T|wi) must lie in [0, 1]");
    mNet.validate("m_net", kFamilyMInputs, 3 * colour.functions(), OutputFunction::Identity,
                  "the colour functions combine its outputs before exp");
    tNet.checkFiniteOnUnitInputs("t_net");
    mNet.checkFiniteOnUnitInputs("m_net");
    if (!masking.empty() && masking.size() != kMaskingCoefficients * kFamilyMaskingFeatures)
        throw InputError("r_lobe.masking: expected " + std::to_string(kMaskingCoefficients) +
                         " rows of " + std::to_string(kFamilyMaskingFeatures) + " coefficients");
    for (double c : masking)
        if (!std::isfinite(c)) throw InputError("r_lobe.masking: a coefficient is not finite");
    sampling.validate();
    calibration.validate("energy_calibration");
    // What the renderer needs of every yarn (shapes within its networks'
    // capacity) holds for all when it holds for one: at() changes biases only.
    at(centre(), "box centre");
}

YarnModel FamilyModel::at(const YarnPoint& p, const std::string& what) const {
    box.check(p, what);
    const auto q = box.normalised(p);
    YarnModel m;
    m.fiber = {p.cR, Rgb(kFamilyGatheredCTT), p.betaRDeg, p.betaTTDeg, p.gammaTTDeg};
    m.ply = {p.fibers, p.density, p.twist};
    try {
        m.fiber.validate(what);
        m.ply.validate();
    } catch (const InputError& e) {
        throw InputError(what + ": " + e.what());
    }
    m.tNet = foldConstantInputs(tNet, 3, {q[0], q[1], q[2]});
    m.mNet = foldConstantInputs(mNet, 6, std::vector<double>(q.begin(), q.end()));
    m.rLobe.tiltDeg = SurfaceFiberFrame::tiltDegOfTwist(p.twist);
    if (!masking.empty()) {
        const auto f = familyMaskingFeatures(box, p);
        m.rLobe.masking.assign(kMaskingCoefficients, 0.0);
        for (int k = 0; k < kMaskingCoefficients; ++k)
            for (int l = 0; l < kFamilyMaskingFeatures; ++l)
                m.rLobe.masking[k] += masking[k * kFamilyMaskingFeatures + l] * f[l];
    }
    m.sampling = sampling;
    m.colour = colour;
    m.colourCalibration = calibration.at(box, p);
    m.fit = {{"family", {{"yarn", p.toJson()}, {"box", box.toJson()}}}};
    m.validate();
    return m;
}

json familyModelToJson(const FamilyModel& model) {
    json masking = nullptr;
    if (!model.masking.empty())
        masking = {{"form", kMaskingForm},
                   {"features", kMaskingFeatures},
                   {"coefficients", coefficientRows(model.masking, kFamilyMaskingFeatures)}};
    json document = {{"format", kFamilyModelFormat},
                     {"version", 1},
                     {"box", model.box.toJson()},
                     {"colour", model.colour.toJson()},
                     {"t_net", modelNetworkToJson(model.tNet)},
                     {"m_net", modelNetworkToJson(model.mNet)},
                     {"r_lobe", {{"masking", masking}}},
                     {"sampling", modelSamplingToJson(model.sampling)},
                     {"fit", model.fit}};
    // Version 2 only with a calibration: a file without one stays readable
    // by version 1 readers.
    const FamilyCalibration& cal = model.calibration;
    if (!cal.empty()) {
        json m = json::array();
        for (const std::vector<double>& block : cal.m)
            m.push_back(coefficientRows(block, kFamilyCalibrationFeatures));
        document["version"] = kFamilyModelVersion;
        document["energy_calibration"] = {{"form", kCalibrationForm},
                                          {"features", kCalibrationFeatures},
                                          {"degree", cal.degree},
                                          {"c_tt", cal.cTT},
                                          {"r", coefficientRows(cal.r, kFamilyCalibrationFeatures)},
                                          {"m", m}};
    }
    return document;
}

namespace {

FamilyCalibration readFamilyCalibration(const JsonObjectReader& r) {
    r.oneOf("form", {kCalibrationForm});
    r.oneOf("features", {kCalibrationFeatures});
    FamilyCalibration cal;
    cal.degree = static_cast<int>(r.integer("degree", {0, EnergyCalibration::kMaxDegree}));
    const size_t terms = static_cast<size_t>(EnergyCalibration::termCount(cal.degree));
    cal.cTT = readCalibrationNodeColours(r);
    readCoefficientRows(r.value("r"), r.source(), r.pathOf("r"), terms, kFamilyCalibrationFeatures,
                        &cal.r);
    const json& perNode = r.value("m");
    if (!perNode.is_array() || perNode.size() != cal.cTT.size())
        r.fail("m", "expected one block of rows per node colour (" +
                        std::to_string(cal.cTT.size()) + "), got " + describeJson(perNode));
    cal.m.resize(cal.cTT.size());
    for (size_t g = 0; g < cal.cTT.size(); ++g)
        readCoefficientRows(perNode[g], r.source(), jsonIndexPath(r.pathOf("m"), g), terms,
                            kFamilyCalibrationFeatures, &cal.m[g]);
    return cal;
}

}  // namespace

bool isFamilyModelDocument(const json& j) {
    return j.is_object() && j.contains("format") && j["format"] == kFamilyModelFormat;
}

FamilyModel familyModelFromJson(const json& j, const std::string& source) {
    if (!j.is_object())
        throwJsonError(source, "",
                       std::string("expected an object (a ") + kFamilyModelFormat + " file), got " +
                           describeJson(j));
    JsonObjectReader r(j, source);
    if (!r.has("format"))
        r.fail(std::string("missing key \"format\" (expected \"") + kFamilyModelFormat + "\")");
    r.oneOf("format", {kFamilyModelFormat});
    const int64_t version = r.integer("version");
    if (version < 1 || version > kFamilyModelVersion)
        r.fail("version", "unsupported version " + describeJson(r.value("version")) +
                              " (supported: 1 to " + std::to_string(kFamilyModelVersion) + ")");
    if (version == 1)
        r.allowKeys(
            {"format", "version", "box", "colour", "t_net", "m_net", "r_lobe", "sampling", "fit"});
    else
        r.allowKeys({"format", "version", "box", "colour", "t_net", "m_net", "r_lobe", "sampling",
                     "energy_calibration", "fit"});
    FamilyModel model;
    model.box = FamilyBox::fromJson(r.value("box"), source + ": box");
    model.colour = ColourBasis::fromJson(r.value("colour"), source + ": colour");
    model.tNet = readModelNetwork(r, "t_net", kFamilyTInputs, 1);
    model.mNet = readModelNetwork(r, "m_net", kFamilyMInputs, 3 * model.colour.functions());
    const JsonObjectReader rLobe = r.object("r_lobe", {"masking"});
    if (!rLobe.isNull("masking")) {
        const JsonObjectReader m = rLobe.object("masking", {"form", "features", "coefficients"});
        m.oneOf("form", {kMaskingForm});
        m.oneOf("features", {kMaskingFeatures});
        readCoefficientRows(m.value("coefficients"), source, m.pathOf("coefficients"),
                            kMaskingCoefficients, kFamilyMaskingFeatures, &model.masking);
    }
    model.sampling = readModelSampling(r);
    if (version >= 2 && !r.isNull("energy_calibration"))
        model.calibration = readFamilyCalibration(
            r.object("energy_calibration", {"form", "features", "degree", "c_tt", "r", "m"}));
    r.object("fit");  // an object, written back as is
    model.fit = r.value("fit");
    try {
        model.validate();
    } catch (const InputError& e) {
        throw InputError(source + ": " + e.what());
    }
    return model;
}

FamilyModel loadFamilyModel(const std::string& path) {
    return familyModelFromJson(readJsonFile(path), path);
}

void saveFamilyModel(const FamilyModel& model, const std::string& path) {
    const json j = familyModelToJson(model);
    familyModelFromJson(j, path);
    writeFileAtomic(path, formatModelJson(j));
}

ModelFile ModelFile::load(const std::string& path) {
    const json document = readJsonFile(path);
    ModelFile file;
    file.path = path;
    if (isFamilyModelDocument(document))
        file.family = familyModelFromJson(document, path);
    else
        file.single = yarnModelFromJson(document, path);
    return file;
}

YarnModel ModelFile::forYarn(const std::optional<YarnPoint>& yarn, const std::string& owner,
                             const std::string& yarnWhat, const std::string& yarnHint) const {
    if (single) {
        if (yarn)
            throw InputError(yarnWhat + ": " + path +
                             " is a model of one yarn; only a family model (weft fit family) "
                             "takes yarn parameters");
        return *single;
    }
    if (!yarn)
        throw InputError(owner + ": " + path +
                         " is a family model (weft fit family): give the yarn's parameters " +
                         yarnHint + " (docs/family.md)");
    return family->at(*yarn, yarnWhat);
}

}  // namespace weft
