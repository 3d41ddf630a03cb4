// The yarn parameters of a family and their box (family_box.h).
#include "weft/core/family_box.h"

#include <cmath>

#include "weft/core/error.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"

namespace weft {

namespace {

// The parameters of a box in unit-cube order (C_R once: its range holds for
// each channel), with their JSON names.
struct BoxField {
    const char* name;
    ParameterRange FamilyBox::*range;
};
constexpr BoxField kBoxFields[] = {
    {"fibers", &FamilyBox::fibers},
    {"density", &FamilyBox::density},
    {"twist", &FamilyBox::twist},
    {"beta_r_deg", &FamilyBox::betaRDeg},
    {"beta_tt_deg", &FamilyBox::betaTTDeg},
    {"gamma_tt_deg", &FamilyBox::gammaTTDeg},
    {"c_r", &FamilyBox::cR},
};

// The Halton sequence's bases: one prime per dimension.
constexpr int kHaltonBases[FamilyBox::kDimensions] = {2, 3, 5, 7, 11, 13, 17, 19, 23};

// The radical inverse of `index` in `base`: its digits mirrored about the point.
double radicalInverse(uint64_t index, int base) {
    const double inverseBase = 1.0 / base;
    double value = 0, scale = inverseBase;
    for (; index > 0; index /= base, scale *= inverseBase)
        value += static_cast<double>(index % base) * scale;
    return value;
}

}  // namespace

nlohmann::json YarnPoint::toJson() const {
    return {{"fibers", fibers},         {"density", density},       {"twist", twist},
            {"beta_r_deg", betaRDeg},   {"beta_tt_deg", betaTTDeg}, {"gamma_tt_deg", gammaTTDeg},
            {"c_r", {cR.r, cR.g, cR.b}}};
}

YarnPoint YarnPoint::fromJson(const nlohmann::json& j, const std::string& source,
                              const std::string& path,
                              std::initializer_list<std::string_view> extraKeys) {
    // The caller's keys are its own to read.
    nlohmann::json own = j;
    if (own.is_object())
        for (const std::string_view key : extraKeys) own.erase(std::string(key));
    JsonObjectReader r(own, source, path);
    r.allowKeys({"fibers", "density", "twist", "beta_r_deg", "beta_tt_deg", "gamma_tt_deg", "c_r"});
    YarnPoint p;
    p.fibers = static_cast<int>(r.integer("fibers", {1, INT32_MAX}));
    p.density = r.number("density", NumberRange::open(0, 1));
    p.twist = r.number("twist", NumberRange::atLeast(0));
    const NumberRange angle = NumberRange::openClosed(0, 90).with("degrees");
    p.betaRDeg = r.number("beta_r_deg", angle);
    p.betaTTDeg = r.number("beta_tt_deg", angle);
    p.gammaTTDeg = r.number("gamma_tt_deg", angle);
    const std::vector<double> cR = r.numbers("c_r", 3, NumberRange::closed(0, 1), "(r, g, b)");
    p.cR = Rgb(cR[0], cR[1], cR[2]);
    return p;
}

void FamilyBox::validate(const std::string& source) const {
    for (const BoxField& f : kBoxFields) {
        const ParameterRange& r = this->*f.range;
        if (!std::isfinite(r.lo) || !std::isfinite(r.hi) || r.lo > r.hi)
            throw InputError(source + ": " + f.name + " = [" + formatNumber(r.lo) + ", " +
                             formatNumber(r.hi) + "]: expected [lo, hi] with finite lo <= hi");
    }
    if (fibers.lo != std::floor(fibers.lo) || fibers.hi != std::floor(fibers.hi) || fibers.lo < 1 ||
        fibers.hi > INT32_MAX)
        throw InputError(source + ": fibers = [" + formatNumber(fibers.lo) + ", " +
                         formatNumber(fibers.hi) + "]: expected whole numbers of fibers, >= 1");
}

FamilyBox FamilyBox::fromJson(const nlohmann::json& j, const std::string& source) {
    JsonObjectReader r(j, source);
    r.allowKeys({"fibers", "density", "twist", "beta_r_deg", "beta_tt_deg", "gamma_tt_deg", "c_r"});
    FamilyBox box;
    for (const BoxField& f : kBoxFields) {
        const std::vector<double> v = r.numbers(f.name, 2, {}, "[lo, hi]");
        box.*f.range = {v[0], v[1]};
    }
    box.validate(source);
    return box;
}

FamilyBox FamilyBox::fromJsonFile(const std::string& path) {
    return fromJson(readJsonFile(path), path);
}

nlohmann::json FamilyBox::toJson() const {
    nlohmann::json j = nlohmann::json::object();
    for (const BoxField& f : kBoxFields) j[f.name] = {(this->*f.range).lo, (this->*f.range).hi};
    return j;
}

YarnPoint FamilyBox::at(const std::array<double, kDimensions>& u) const {
    YarnPoint p;
    p.fibers = static_cast<int>(std::lround(fibers.at(u[0])));
    p.density = density.at(u[1]);
    p.twist = twist.at(u[2]);
    p.betaRDeg = betaRDeg.at(u[3]);
    p.betaTTDeg = betaTTDeg.at(u[4]);
    p.gammaTTDeg = gammaTTDeg.at(u[5]);
    p.cR = Rgb(cR.at(u[6]), cR.at(u[7]), cR.at(u[8]));
    return p;
}

std::array<double, FamilyBox::kDimensions> FamilyBox::normalised(const YarnPoint& p) const {
    const auto q = [](double v, const ParameterRange& r) {
        return r.hi > r.lo ? 2.0 * (v - r.lo) / (r.hi - r.lo) - 1.0 : 0.0;
    };
    return {q(p.fibers, fibers),
            q(p.density, density),
            q(p.twist, twist),
            q(p.betaRDeg, betaRDeg),
            q(p.betaTTDeg, betaTTDeg),
            q(p.gammaTTDeg, gammaTTDeg),
            q(p.cR.r, cR),
            q(p.cR.g, cR),
            q(p.cR.b, cR)};
}

void FamilyBox::check(const YarnPoint& p, const std::string& source) const {
    const auto inside = [&](const char* field, double v, const ParameterRange& r) {
        if (!(v >= r.lo && v <= r.hi))
            throw InputError(source + ": " + field + " = " + formatNumber(v) +
                             " is outside the family's box: allowed [" + formatNumber(r.lo) + ", " +
                             formatNumber(r.hi) + "]");
    };
    inside("fibers", p.fibers, fibers);
    inside("density", p.density, density);
    inside("twist", p.twist, twist);
    inside("beta_r_deg", p.betaRDeg, betaRDeg);
    inside("beta_tt_deg", p.betaTTDeg, betaTTDeg);
    inside("gamma_tt_deg", p.gammaTTDeg, gammaTTDeg);
    for (int c = 0; c < 3; ++c) inside(("c_r[" + std::to_string(c) + "]").c_str(), p.cR[c], cR);
}

const char* familyDesignName(FamilyDesign design) {
    return design == FamilyDesign::Edges ? "edges" : "halton";
}

FamilyDesign parseFamilyDesign(const std::string& name, const std::string& what) {
    if (name == "halton") return FamilyDesign::Halton;
    if (name == "edges") return FamilyDesign::Edges;
    throw InputError(what + ": \"" + name + "\" is not a design (allowed: halton, edges)");
}

std::vector<YarnPoint> familyPoints(const FamilyBox& box, int count, uint64_t seed,
                                    FamilyDesign design) {
    Rng rng(0x46616d696c79ULL, seed);  // the rotation's own stream ("Family")
    std::array<double, FamilyBox::kDimensions> offset;
    for (double& o : offset) o = rng.uniform();
    std::vector<YarnPoint> points;
    points.reserve(count);
    for (int k = 0; k < count; ++k) {
        std::array<double, FamilyBox::kDimensions> u;
        for (int d = 0; d < FamilyBox::kDimensions; ++d) {
            const double v =
                radicalInverse(static_cast<uint64_t>(k) + 1, kHaltonBases[d]) + offset[d];
            u[d] = v >= 1 ? v - 1 : v;
            if (design == FamilyDesign::Edges) u[d] = 0.5 * (1 - std::cos(kPi * u[d]));
        }
        points.push_back(box.at(u));
    }
    return points;
}

}  // namespace weft
