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

}  // namespace weft
