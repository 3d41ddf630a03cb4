#include "weft/yarn/energy_calibration.h"

#include <algorithm>
#include <cmath>

#include "weft/core/error.h"

namespace weft {

void EnergyCalibration::basis(const Vec3& w, int degree, double* out) {
    double yPow[kMaxDegree + 1], zPow[kMaxDegree + 1];
    yPow[0] = zPow[0] = 1;
    for (int k = 1; k <= degree; ++k) yPow[k] = yPow[k - 1] * w.y, zPow[k] = zPow[k - 1] * w.z;
    int n = 0;
    for (int a = 0; a <= std::min(1, degree); ++a) {
        const double xa = a ? w.x : 1.0;
        for (int b = 0; b <= degree - a; ++b)
            for (int c = 0; c <= degree - a - b; ++c) out[n++] = xa * yPow[b] * zPow[c];
    }
}

int EnergyCalibration::termIndex(int a, int b, int c, int degree) {
    // a = 0 holds (degree + 1)(degree + 2) / 2 terms; within a, b = j holds degree - a - j + 1.
    int index = a ? (degree + 1) * (degree + 2) / 2 : 0;
    for (int j = 0; j < b; ++j) index += degree - a - j + 1;
    return index + c;
}

EnergyCalibration::Scales EnergyCalibration::scales(const Vec3& wi) const {
    Scales s;
    if (empty()) return s;
    double f[termCount(kMaxDegree)];
    basis(wi, degree, f);
    const int n = termCount(degree);
    // Six dot products (R and M per channel), each in four interleaved partial
    // sums: independent chains of multiply-adds, where one running sum made a
    // chain of n dependent additions (most of the yarn BSDF's prepare).
    for (int j = 0; j < 6; ++j) {
        const double* c = (j < 3 ? r[j] : m[j - 3]).data();
        double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
        int k = 0;
        for (; k + 4 <= n; k += 4) {
            s0 += c[k] * f[k];
            s1 += c[k + 1] * f[k + 1];
            s2 += c[k + 2] * f[k + 2];
            s3 += c[k + 3] * f[k + 3];
        }
        for (; k < n; ++k) s0 += c[k] * f[k];
        const double logScale = (s0 + s2) + (s1 + s3);
        (j < 3 ? s.r : s.m)[j % 3] = std::exp(std::clamp(logScale, -kMaxLogScale, kMaxLogScale));
    }
    return s;
}

double ColourCalibration::variableOf(double c) { return std::sqrt(-std::log(c)); }

void ColourCalibration::validate(const std::string& what) const {
    if (nodes.empty() || nodes.size() != cTT.size() || nodes.size() > kMaxNodes)
        throw InputError(what + ": expected one calibration per node colour, 1 to " +
                         std::to_string(kMaxNodes) + " of them, got " +
                         std::to_string(nodes.size()) + " for " + std::to_string(cTT.size()) +
                         " colours");
    validateNodeColours(cTT, what);
    for (size_t g = 0; g < cTT.size(); ++g) {
        const EnergyCalibration& n = nodes[g];
        const size_t terms = static_cast<size_t>(EnergyCalibration::termCount(n.degree));
        if (n.degree != nodes[0].degree || n.degree < 0 || n.degree > EnergyCalibration::kMaxDegree)
            throw InputError(what + ": node " + std::to_string(g) + " has degree " +
                             std::to_string(n.degree) +
                             "; every node needs the same degree in [0, " +
                             std::to_string(EnergyCalibration::kMaxDegree) + "]");
        for (int c = 0; c < 3; ++c)
            if (n.r[c].size() != terms || n.m[c].size() != terms)
                throw InputError(what + ": node " + std::to_string(g) + " needs " +
                                 std::to_string(terms) + " coefficients per channel for R and M");
    }
}

void ColourCalibration::validateNodeColours(const std::vector<double>& cTT,
                                            const std::string& what) {
    for (size_t g = 0; g < cTT.size(); ++g)
        if (!(cTT[g] > 0 && cTT[g] <= 1) || (g > 0 && !(cTT[g] > cTT[g - 1])))
            throw InputError(what + ".c_tt[" + std::to_string(g) +
                             "]: node colours must increase strictly within (0, 1]");
}

EnergyCalibration ColourCalibration::at(const Rgb& colour) const {
    EnergyCalibration cal;
    if (empty()) return cal;
    cal.degree = nodes[0].degree;
    const size_t last = cTT.size() - 1;
    for (int c = 0; c < 3; ++c) {
        // The interval [g, g + 1] around the channel's colour and the weight of g + 1.
        const double x = std::clamp(colour[c], cTT.front(), cTT.back());
        size_t g = 0;
        while (g + 1 < last && x > cTT[g + 1]) ++g;
        double t = 0;
        if (last > 0) {
            const double u0 = variableOf(cTT[g]), u1 = variableOf(cTT[g + 1]);
            t = std::clamp((variableOf(x) - u0) / (u1 - u0), 0.0, 1.0);
        }
        const EnergyCalibration& a = nodes[g];
        const EnergyCalibration& b = nodes[std::min(g + 1, last)];
        cal.r[c].resize(a.r[c].size());
        cal.m[c].resize(a.m[c].size());
        for (size_t k = 0; k < a.r[c].size(); ++k) {
            cal.r[c][k] = (1 - t) * a.r[c][k] + t * b.r[c][k];
            cal.m[c][k] = (1 - t) * a.m[c][k] + t * b.m[c][k];
        }
    }
    return cal;
}

}  // namespace weft
