#include "weft/yarn/energy_calibration.h"

#include <algorithm>
#include <cmath>

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
    for (int ch = 0; ch < 3; ++ch) {
        double lr = 0, lm = 0;
        for (int k = 0; k < n; ++k) lr += r[ch][k] * f[k], lm += m[ch][k] * f[k];
        s.r[ch] = std::exp(std::clamp(lr, -kMaxLogScale, kMaxLogScale));
        s.m[ch] = std::exp(std::clamp(lm, -kMaxLogScale, kMaxLogScale));
    }
    return s;
}

}  // namespace weft
