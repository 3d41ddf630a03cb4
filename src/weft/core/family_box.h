// weft/core/family_box.h — the yarn parameters of a family model and the box
// they range over (issue 42; docs/family.md).
//
// A family model gives the yarn BSDF anywhere in a box of yarn parameters:
// the ply's fiber count N, fiber density rho and twist alpha, and the fiber's
// lobe widths beta_R, beta_TT, gamma_TT and reflectance C_R (docs/design.md
// 3-4). C_TT is not among them: a family is an any-colour model (the walks
// record what any C_TT needs, gather/colour_paths.h). The gather (which
// walks the yarns of the box), the fit and the renderer (which checks a
// scene's yarns against a model's box) share these types, so they live here.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/rgb.h"

namespace weft {

// One yarn of a family.
struct YarnPoint {
    int fibers = 0;                 // N
    double density = 0, twist = 0;  // rho, alpha
    double betaRDeg = 0, betaTTDeg = 0, gammaTTDeg = 0;
    Rgb cR;

    // {"fibers", "density", "twist", "beta_r_deg", "beta_tt_deg", "gamma_tt_deg", "c_r"}.
    nlohmann::json toJson() const;
    // Strict; `extraKeys` may also appear (a family.json entry's "folder").
    static YarnPoint fromJson(const nlohmann::json& j, const std::string& source,
                              const std::string& path,
                              std::initializer_list<std::string_view> extraKeys = {});
    bool operator==(const YarnPoint&) const = default;
};

struct ParameterRange {
    double lo = 0, hi = 0;
    bool contains(double v) const { return v >= lo && v <= hi; }
    double at(double u) const { return lo + (hi - lo) * u; }
};

// The box of a family: a range per parameter; C_R's range holds for each
// channel. The defaults are the box of issue 42, which holds the paper's
// five materials (yarn/material_preset.h).
struct FamilyBox {
    ParameterRange fibers{200, 600}, density{0.2, 0.4}, twist{0, 0.3};
    ParameterRange betaRDeg{1, 8}, betaTTDeg{10, 28}, gammaTTDeg{19, 39};
    ParameterRange cR{0, 1};
    // Unit-cube dimensions: N, rho, alpha, beta_R, beta_TT, gamma_TT, C_R r, g, b.
    static constexpr int kDimensions = 9;

    // InputError naming `source` and the field unless every range is finite
    // with lo <= hi and N's bounds are whole numbers >= 1. (Whether its
    // corners are a ply and a fiber is the gather's check: gather/family.h.)
    void validate(const std::string& source) const;
    // {"fibers": [lo, hi], ..., "c_r": [lo, hi]}: every key required, strict, validated.
    static FamilyBox fromJson(const nlohmann::json& j, const std::string& source);
    static FamilyBox fromJsonFile(const std::string& path);
    nlohmann::json toJson() const;

    // The yarn at u in [0, 1)^kDimensions (N rounded to the nearest integer).
    YarnPoint at(const std::array<double, kDimensions>& u) const;
    // A family model's network inputs for p (yarn/family_model.h): each
    // parameter, in unit-cube order, mapped from its range to [-1, 1]
    // linearly (0 for a range of zero width).
    std::array<double, kDimensions> normalised(const YarnPoint& p) const;
    // InputError naming `source`, the field, its value and the box's range
    // when p lies outside.
    void check(const YarnPoint& p, const std::string& source) const;
};

// How a family's yarns spread over the box.
//   Halton: uniform in the box.
//   Edges:  each unit-cube coordinate u mapped to (1 - cos(pi u)) / 2 (the
//           arcsine law, the Chebyshev nodes' spacing): denser towards every
//           face. The paper's materials sit on the box's faces and corners
//           (silk on five faces at once: beta_R, beta_TT, gamma_TT, rho,
//           alpha), where a uniform design has few yarns; this design has
//           about 3x the yarns within 5% of a face in each dimension.
enum class FamilyDesign { Halton, Edges };
const char* familyDesignName(FamilyDesign design);  // "halton", "edges"
// InputError naming `what` and the allowed names otherwise.
FamilyDesign parseFamilyDesign(const std::string& name, const std::string& what);

// `count` yarns of the box: the Halton sequence (bases 2, 3, 5, ..., 23) from
// index 1, each dimension shifted modulo 1 by an offset drawn from `seed`
// (a Cranley-Patterson rotation: another well-spread set for every seed),
// then mapped by `design`.
std::vector<YarnPoint> familyPoints(const FamilyBox& box, int count, uint64_t seed,
                                    FamilyDesign design = FamilyDesign::Halton);

}  // namespace weft
