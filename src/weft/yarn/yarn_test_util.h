// weft/yarn/yarn_test_util.h — yarn models for the tests of yarn/ and fit/.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/rng.h"
#include "weft/core/sampling.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_model.h"

namespace weft::testing {

// The committed test models (tests/data/README.md): "fleece-small", "gabardine-small".
inline std::string testModelPath(const std::string& name) {
    return std::string(WEFT_SOURCE_DIR) + "/tests/data/" + name + ".json";
}

// `model` with a hand-set energy calibration: S_R times 1/2 and S_M times 2 exp(0.3 x).
inline YarnModel withCalibration(YarnModel model) {
    model.calibration.degree = 1;
    for (int c = 0; c < 3; ++c) {
        model.calibration.r[c] = {-std::log(2.0), 0, 0, 0};
        model.calibration.m[c] = {std::log(2.0), 0, 0, 0.3};  // 1, z, y, x
    }
    return model;
}

// Chi-square of `n` samples of bsdf.sample(wi) against bsdf.pdf on `grid`,
// whose cells are taken in the surface fiber frame (`inFiberFrame`, where the
// R lobe is a band of theta) or the yarn frame; the delta T lobe is one more
// cell, expected n P_T times. The generator is seeded by `seed` and wi.
inline Chi2Result yarnSamplingChi2(const YarnBsdf& bsdf, const Vec3& wi, const SphereGrid& grid,
                                   int64_t n, uint64_t seed, bool inFiberFrame) {
    const SurfaceFiberFrame identity;
    const SurfaceFiberFrame& frame = inFiberFrame ? bsdf.model().frame() : identity;
    std::vector<double> observed(grid.cells() + 1, 0);
    Rng rng(seed, static_cast<uint64_t>(1e6 * (wi.x + 2 * wi.y + 3 * wi.z) + 1e7));
    for (int64_t k = 0; k < n; ++k) {
        const BsdfSample s = bsdf.sample(wi, {rng.uniform(), rng.uniform(), rng.uniform()}, rng);
        if (!s.valid()) ADD_FAILURE() << "invalid sample at wi " << wi;
        observed[s.isDelta ? grid.cells() : grid.cellOf(frame.toLocal(s.wo))] += 1;
    }
    std::vector<double> expected =
        grid.expectedCounts([&](const Vec3& local) { return bsdf.pdf(wi, frame.fromLocal(local)); },
                            static_cast<double>(n));
    expected.push_back(static_cast<double>(n) * bsdf.lobeProbabilities(wi).t);
    return chi2Test(observed, expected);
}

// `count` random queries of `bsdf` for the batch tests (the batches must
// give the single calls' bits): wi and wo uniform on the sphere, sample
// inputs, an importance per query; each incident prepared alone (`single`)
// and by one prepareBatch (`batch`); a generator per query for the single
// calls and a copy of it for the batch (`rngSingle`, `rngBatch` and
// `rngPtr`, on stream `rngStream`).
struct BatchQueries {
    std::vector<Vec3> wi, wo;
    std::vector<BsdfSampleInput> u;
    std::vector<BsdfIncident> single, batch;
    std::vector<const BsdfIncident*> batchConst;
    std::vector<Rng> rngSingle, rngBatch;
    std::vector<Rng*> rngPtr;

    BatchQueries(const Bsdf& bsdf, size_t count, Rng& rng, uint64_t rngStream)
        : wi(count),
          wo(count),
          u(count),
          single(count),
          batch(count),
          batchConst(count),
          rngPtr(count) {
        std::vector<BsdfIncident*> batchPtr(count);
        for (size_t k = 0; k < count; ++k) {
            wi[k] = sampleUniformSphere(rng.uniform(), rng.uniform());
            wo[k] = sampleUniformSphere(rng.uniform(), rng.uniform());
            u[k] = {rng.uniform(), rng.uniform(), rng.uniform()};
            const Rgb importance(rng.uniform(), rng.uniform(), rng.uniform());
            single[k].setImportance(importance);
            batch[k].setImportance(importance);
            bsdf.prepare(wi[k], single[k]);
            batchPtr[k] = &batch[k];
            batchConst[k] = &batch[k];
            rngSingle.push_back(Rng(k, rngStream));
        }
        bsdf.prepareBatch(wi.data(), batchPtr.data(), count);
        rngBatch = rngSingle;
        for (size_t k = 0; k < count; ++k) rngPtr[k] = &rngBatch[k];
    }
};

}  // namespace weft::testing
