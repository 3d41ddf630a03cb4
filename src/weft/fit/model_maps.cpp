#include "weft/fit/model_maps.h"

#include <tbb/parallel_for.h>

#include "weft/fit/mlp.h"
#include "weft/yarn/fixed_mlp.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

std::vector<double> transmissionMap(const NetworkWeights& tNet, const RdmBins& bins) {
    const TransmissionMlp net(tNet, "t_net");
    std::vector<double> pT(bins.incidentCount());
    for (size_t i = 0; i < pT.size(); ++i) pT[i] = evalTransmission(net, bins.incidentCentre(i));
    return pT;
}

std::vector<double> modelTransmissionMap(const YarnModel& model, const RdmBins& bins) {
    if (!model.hasTransmissionLobe()) return std::vector<double>(bins.incidentCount(), 0.0);
    return transmissionMap(model.tNet, bins);
}

std::vector<float> modelReflectionMap(const YarnModel& model, const RdmBins& bins) {
    if (!model.hasReflectionLobe())
        return std::vector<float>(bins.incidentCount() * bins.outgoingCount() * 3, 0.0f);
    const std::vector<double> pT = modelTransmissionMap(model, bins);
    const RLobe lobe(model.fiber, model.rLobe);
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    std::vector<float> map(nIn * nOut * 3);
    tbb::parallel_for(size_t(0), nIn, [&](size_t i) {
        const Vec3 wi = bins.incidentCentre(i);
        const Rgb scale = model.calibration.scales(wi).r;
        for (size_t o = 0; o < nOut; ++o) {
            const Rgb v = lobe.eval(wi, bins.outgoingCentre(o), pT[i]) * scale;
            for (int c = 0; c < 3; ++c) map[(i * nOut + o) * 3 + c] = static_cast<float>(v[c]);
        }
    });
    return map;
}

namespace {

// Runs `net` (inputs (wi, wo)) on every pair of bin centres, one incident bin
// at a time in parallel, and lets store(i, wi, y) write that bin's part of a
// (TI, PI, TO, PO, 3) map from the outputs y (outputs x TO PO).
template <typename Store>
std::vector<float> mapOverBinCentres(const Mlp<float>& net, const RdmBins& bins,
                                     const Store& store) {
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    std::vector<Vec3> outgoing(nOut);
    for (size_t o = 0; o < nOut; ++o) outgoing[o] = bins.outgoingCentre(o);
    std::vector<float> map(nIn * nOut * 3);
    tbb::parallel_for(size_t(0), nIn, [&](size_t i) {
        Mlp<float>::Matrix x(6, static_cast<Eigen::Index>(nOut));
        const Vec3 wi = bins.incidentCentre(i);
        for (size_t o = 0; o < nOut; ++o)
            setInputColumn(x, static_cast<Eigen::Index>(o), wi, outgoing[o]);
        store(wi, net.forward(x), &map[i * nOut * 3]);
    });
    return map;
}

}  // namespace

std::vector<float> modelMultipleScatteringMap(const YarnModel& model, const RdmBins& bins) {
    // A conditioned model at its own colour (yarn_model.h).
    const Mlp<float> net(model.colour
                             ? foldColourIntoNetwork(model.mNet, *model.colour, model.fiber.cTT)
                             : model.mNet);
    return mapOverBinCentres(net, bins,
                             [&](const Vec3& wi, const Mlp<float>::Matrix& y, float* out) {
                                 const Rgb scale = model.calibration.scales(wi).m;
                                 for (Eigen::Index o = 0; o < y.cols(); ++o)
                                     for (int c = 0; c < 3; ++c)
                                         out[o * 3 + c] = static_cast<float>(y(c, o) * scale[c]);
                             });
}

std::vector<float> conditionedMultipleScatteringMap(const NetworkWeights& mNet,
                                                    const ColourBasis& basis, const RdmBins& bins,
                                                    const Rgb& cTT) {
    return mapOverBinCentres(Mlp<float>(mNet), bins,
                             [&](const Vec3&, const Mlp<float>::Matrix& y, float* out) {
                                 for (Eigen::Index o = 0; o < y.cols(); ++o) {
                                     const Rgb m = conditionedM(y.col(o).data(), basis, cTT);
                                     for (int c = 0; c < 3; ++c)
                                         out[o * 3 + c] = static_cast<float>(m[c]);
                                 }
                             });
}

}  // namespace weft
