// weft/yarn/yarn_incident.h — what the yarn BSDF computes once per incident direction.
//
// YarnBsdf::prepare(wi) fills one YarnIncident and keeps it in the caller's
// BsdfIncident (core/bsdf.h): the model's part (YarnEvaluator::prepare) and
// the sampler's part (YarnSampler::prepare), so that eval, pdf and sample at
// many wo pay for wi once.
#pragma once

#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/yarn/sampling_table.h"

namespace weft {

// A direction's angles in the surface fiber frame (yarn_lobes.h): the local
// direction, the fiber model's angles (the R lobe's), and the azimuth from n,
// phi = atan2(y, max(z, 0)), which the energy guard's R table and the
// sampling table share (one atan2 each for theta and phi per wi).
struct SurfaceFiberAngles {
    Vec3 local;
    FiberBcsdf::Angles angles{};
    double phi = 0;
};

// The yarn BSDF's state for one incident direction. Trivially copyable: it
// travels as the bytes of a BsdfIncident.
struct YarnIncident {
    // wi was below the surface (wi.z < 0): the BSDF is two-sided by mirroring
    // wi and every wo through the surface plane (yarn_bsdf.h).
    bool mirrored = false;
    Vec3 wi;  // in the upper hemisphere (mirrored if it was below)

    // The model's value at wi (YarnEvaluator::prepare): P(T|wi), the factor on
    // S_R (the energy calibration) and on S_M (the calibration times the
    // energy guard), and the R lobe's fiber state (surface fiber frame).
    double pT = 0;
    Rgb rScale, mScale;
    FiberBcsdf::Incident fiber{};

    // The sampler's choice at wi (YarnSampler::prepare): the probability of
    // the delta T lobe; tabulated sampling also keeps the share of q_R in the
    // continuous part, theta_i in the surface fiber frame, and the sampling
    // table laid out at wi.
    double pickT = 0, pickR = 0, thetaI = 0;
    SamplingTable::Layout table;
    // With exit offsets (yarn_bsdf.h, ExitSpread), set by YarnBsdf::prepare,
    // which sees the path's importance (core/bsdf.h): the probability of each
    // channel for the exit offset (mostly in proportion to the M light each
    // carries, among the channels with M light in wi's cell, yarn_bsdf.h; all
    // 0 where the event does not split), and that cell.
    Rgb spreadChannel{0.0};
    int exitCell = 0;
};

}  // namespace weft
