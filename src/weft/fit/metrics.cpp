#include "weft/fit/metrics.h"

#include <cmath>
#include <stdexcept>

namespace weft {

std::vector<size_t> incidentMap(const RdmBins& fine, const RdmBins& coarse) {
    std::vector<size_t> m(fine.incidentCount());
    for (size_t i = 0; i < m.size(); ++i) m[i] = coarse.incidentBin(fine.incidentCentre(i));
    return m;
}

std::vector<size_t> outgoingMap(const RdmBins& fine, const RdmBins& coarse) {
    std::vector<size_t> m(fine.outgoingCount());
    for (size_t o = 0; o < m.size(); ++o) m[o] = coarse.outgoingBin(fine.outgoingCentre(o));
    return m;
}

std::vector<double> poolRdm(const std::vector<float>& map, const RdmBins& fine,
                            const RdmBins& coarse) {
    const size_t nIn = fine.incidentCount(), nOut = fine.outgoingCount();
    if (map.size() != nIn * nOut * 3) throw std::invalid_argument("poolRdm: map size does not match bins");
    const std::vector<size_t> inMap = incidentMap(fine, coarse), outMap = outgoingMap(fine, coarse);
    const size_t cIn = coarse.incidentCount(), cOut = coarse.outgoingCount();
    std::vector<double> pooled(cIn * cOut * 3, 0.0), coarseSolidAngle(cOut, 0.0);
    std::vector<int> incidentCount(cIn, 0);
    std::vector<double> fineSolidAngle(nOut);
    for (size_t o = 0; o < nOut; ++o) {
        fineSolidAngle[o] = fine.outgoingSolidAngle(o);
        coarseSolidAngle[outMap[o]] += fineSolidAngle[o];
    }
    for (size_t i = 0; i < nIn; ++i) ++incidentCount[inMap[i]];
    for (size_t i = 0; i < nIn; ++i) {
        for (size_t o = 0; o < nOut; ++o) {
            const double w = fineSolidAngle[o];
            const size_t cell = (inMap[i] * cOut + outMap[o]) * 3, src = (i * nOut + o) * 3;
            for (int c = 0; c < 3; ++c) pooled[cell + c] += map[src + c] * w;
        }
    }
    for (size_t I = 0; I < cIn; ++I)
        for (size_t O = 0; O < cOut; ++O)
            for (int c = 0; c < 3; ++c) {
                double& v = pooled[(I * cOut + O) * 3 + c];
                v = (incidentCount[I] > 0 && coarseSolidAngle[O] > 0)
                        ? v / (incidentCount[I] * coarseSolidAngle[O])
                        : 0.0;
            }
    return pooled;
}

double coarseRelativeL2(const std::vector<float>& fit, const std::vector<float>& reference,
                        const RdmBins& fine, const RdmBins& coarse) {
    const std::vector<double> a = poolRdm(fit, fine, coarse), b = poolRdm(reference, fine, coarse);
    const size_t cOut = coarse.outgoingCount();
    std::vector<double> solidAngle(cOut);
    for (size_t O = 0; O < cOut; ++O) solidAngle[O] = coarse.outgoingSolidAngle(O);
    double num = 0, den = 0;
    for (size_t k = 0; k < a.size(); ++k) {
        const double w = solidAngle[(k / 3) % cOut];
        num += w * (a[k] - b[k]) * (a[k] - b[k]);
        den += w * b[k] * b[k];
    }
    return den > 0 ? std::sqrt(num / den) : (num > 0 ? INFINITY : 0.0);
}

std::vector<Rgb> incidentEnergies(const std::vector<float>& map, const RdmBins& bins) {
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    if (map.size() != nIn * nOut * 3)
        throw std::invalid_argument("incidentEnergies: map size does not match bins");
    std::vector<Rgb> energy(nIn);
    for (size_t i = 0; i < nIn; ++i)
        for (size_t o = 0; o < nOut; ++o) {
            const double omega = bins.outgoingSolidAngle(o);
            const float* v = &map[(i * nOut + o) * 3];
            for (int c = 0; c < 3; ++c) energy[i][c] += v[c] * omega;
        }
    return energy;
}

double mapEnergy(const std::vector<float>& map, const RdmBins& bins) {
    const std::vector<Rgb> energy = incidentEnergies(map, bins);
    double total = 0, incidentTotal = 0;
    for (size_t i = 0; i < energy.size(); ++i) {
        const double w = bins.incidentSolidAngle(i);
        total += w * energy[i].average();
        incidentTotal += w;
    }
    return total / incidentTotal;
}

TransmissionError transmissionError(const std::vector<double>& pT, const RdmData& rdm) {
    double se = 0, seUnweighted = 0, count = 0;
    for (size_t i = 0; i < pT.size(); ++i) {
        const double d = pT[i] - rdm.pT[i], w = static_cast<double>(rdm.count[i]);
        se += w * d * d;
        seUnweighted += d * d;
        count += w;
    }
    TransmissionError e;
    e.weighted = count > 0 ? std::sqrt(se / count) : 0.0;
    e.unweighted = pT.empty() ? 0.0 : std::sqrt(seUnweighted / static_cast<double>(pT.size()));
    return e;
}

}  // namespace weft
