// weft/core/bsdf.h — the one BSDF contract shared by the fiber and yarn models.
//
// Directions follow Mitsuba/pbrt (docs/design.md 2): wi points towards the previous
// path vertex (camera side), wo towards the next one (light side), both unit
// vectors in the model's local frame.
//   eval(wi, wo)    -> Rgb  scattering value, foreshortening of wo included
//   pdf(wi, wo)     -> solid-angle density of sample() for the continuous lobes
//   evalPdf(wi, wo) -> BsdfEval {eval, pdf} in one call, both exactly equal to
//                      what eval and pdf return
//   sample(wi, u)   -> BsdfSample with weight = eval / pdf, computed in one
//                      place (BsdfSample::fromEval) from one evalPdf
// A sample with pdf == 0 and a black weight is an invalid (absorbed) sample.
//
// class Bsdf is the interface the fiber BCSDF, the yarn BSDF (and any later
// model) implement and the path tracer calls. What depends on wi alone (the
// fiber's incident angles and Fresnel term; the yarn's P(T|wi), calibration
// and energy guard) is computed once by prepare(wi) into a BsdfIncident, a
// fixed-size, trivially copyable value that each BSDF fills with its own
// state; the virtual eval, pdf, evalPdf and sample take that incident, so a
// path tracer that evaluates (NEE) and samples at one vertex pays for it once.
// A BsdfIncident may only be passed to the Bsdf that prepared it. BsdfSlice is
// a Bsdf with wi fixed (the Bsdf and its incident); the (wi, wo) forms on Bsdf
// are defined once below from the virtual ones, so all three ways of asking
// give the same bits. pdf(wi, wo) alone is virtual as well, for a BSDF whose
// density needs much less of wi than prepare() computes (the yarn's needs
// P(T|wi) only, not the calibration and the energy guard: 2.6x faster); an
// override must return exactly pdf(prepared incident, wo).
//
// A BsdfIncident also carries the importance of each colour channel to the
// caller (the path tracer passes the path throughput; default 1, 1, 1). A BSDF
// may pick among its lobes by it, so that a long path's weights stay bounded
// in the channels that carry its light: sample and pdf then both follow that
// choice, and eval does not depend on it. FiberBcsdf does (fiber_bcsdf.h).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <new>
#include <type_traits>

#include "weft/core/rgb.h"
#include "weft/core/rng.h"
#include "weft/core/vec.h"

namespace weft {

// Three uniform numbers in [0, 1) that drive one call to sample(): the first
// picks the lobe, the other two the direction. Samplers that need rejection
// draw further numbers from a generator seeded by these three.
using BsdfSampleInput = std::array<double, 3>;

// The generator sample(wi, u) draws its rejection steps from: seeded by u, so
// that the sample is a deterministic function of (wi, u).
inline Rng bsdfSampleRng(const BsdfSampleInput& u) {
    return Rng(hashDouble(u[0]) ^ (hashDouble(u[1]) >> 1), hashDouble(u[2]));
}

// eval and pdf at one (wi, wo).
struct BsdfEval {
    Rgb value;       // eval(wi, wo), cosine included
    double pdf = 0;  // pdf(wi, wo)
};

struct BsdfSample {
    Vec3 wo;
    Rgb weight;      // eval(wi, wo) / pdf(wi, wo); for a delta lobe the lobe's weight
    double pdf = 0;  // solid-angle density; 0 for a delta lobe or an invalid sample
    int lobe = -1;   // model-specific lobe id, -1 when invalid
    bool isDelta = false;

    bool valid() const { return lobe >= 0; }

    // The sample of a continuous lobe at wo: weight = value / pdf, the one
    // place where it is computed; an invalid sample when pdf is not positive.
    static BsdfSample fromEval(const Vec3& wo, const BsdfEval& e, int lobe) {
        if (!(e.pdf > 0)) return BsdfSample{};
        BsdfSample s;
        s.wo = wo;
        s.pdf = e.pdf;
        s.lobe = lobe;
        s.weight = e.value / e.pdf;
        return s;
    }
};

// wi and a BSDF's state for it (see above). The state is any trivially
// copyable struct of up to kStateBytes bytes, written by emplace and read
// back by get with the same type.
class BsdfIncident {
  public:
    static constexpr size_t kStateBytes = 384;

    const Vec3& wi() const { return wi_; }
    // Set before prepare(). Channels that are negative or not finite count as 0;
    // with no positive channel left, every channel counts as 1.
    void setImportance(const Rgb& importance) {
        Rgb clean;
        for (int c = 0; c < 3; ++c)
            clean[c] = std::isfinite(importance[c]) && importance[c] > 0 ? importance[c] : 0.0;
        importance_ = clean.maxComponent() > 0 ? clean : Rgb(1.0);
    }
    const Rgb& importance() const { return importance_; }

    template <typename T>
    void emplace(const Vec3& wi, const T& state) {
        checkState<T>();
        wi_ = wi;
        ::new (static_cast<void*>(state_)) T(state);
    }
    template <typename T>
    const T& get() const {
        checkState<T>();
        return *std::launder(reinterpret_cast<const T*>(state_));
    }

  private:
    template <typename T>
    static constexpr void checkState() {
        static_assert(std::is_trivially_copyable_v<T>,
                      "a BSDF's incident state is copied as bytes");
        static_assert(sizeof(T) <= kStateBytes, "raise BsdfIncident::kStateBytes");
        static_assert(alignof(T) <= alignof(double), "the state is aligned as a double");
    }

    Vec3 wi_;
    Rgb importance_{1.0};
    alignas(double) unsigned char state_[kStateBytes];
};

class BsdfSlice;
class ExitSpread;

class Bsdf {
  public:
    virtual ~Bsdf() = default;

    // Fills `in` (wi and this BSDF's state, via in.emplace) for eval, pdf,
    // evalPdf and sample below.
    virtual void prepare(const Vec3& wi, BsdfIncident& in) const = 0;
    virtual BsdfEval evalPdf(const BsdfIncident& in, const Vec3& wo) const = 0;
    // The parts of evalPdf; a BSDF overrides them where one is cheaper alone.
    virtual Rgb eval(const BsdfIncident& in, const Vec3& wo) const { return evalPdf(in, wo).value; }
    virtual double pdf(const BsdfIncident& in, const Vec3& wo) const { return evalPdf(in, wo).pdf; }
    // `rng` feeds the rejection steps (e.g. a random walk's own generator).
    virtual BsdfSample sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const = 0;

    // Batches (issue 45): the calls above for `count` queries at once, each
    // result bit for bit the single call's; every in[k] was (or is being)
    // prepared by this BSDF, for any wi. A BSDF overrides them where many
    // queries cost less together (the yarn BSDF's networks run a query per
    // SIMD lane); a path tracer that advances many paths together calls them.
    virtual void prepareBatch(const Vec3* wi, BsdfIncident* const* in, size_t count) const {
        for (size_t k = 0; k < count; ++k) prepare(wi[k], *in[k]);
    }
    virtual void evalPdfBatch(const BsdfIncident* const* in, const Vec3* wo, size_t count,
                              BsdfEval* out) const {
        for (size_t k = 0; k < count; ++k) out[k] = evalPdf(*in[k], wo[k]);
    }
    virtual void sampleBatch(const BsdfIncident* const* in, const BsdfSampleInput* u,
                             Rng* const* rng, size_t count, BsdfSample* out) const {
        for (size_t k = 0; k < count; ++k) out[k] = sample(*in[k], u[k], *rng[k]);
    }
    // True where the batches above are faster than their single calls (the
    // renderer then advances paths together by default).
    virtual bool batchesFaster() const { return false; }
    // A BSDF whose multiply scattered part leaves the surface away from where
    // the light entered (below), or nullptr: every part leaves at the hit.
    virtual const ExitSpread* exitSpread() const { return nullptr; }
    // The same for one (wi, wo): prepare, then the call above.
    Rgb eval(const Vec3& wi, const Vec3& wo) const { return eval(prepared(wi), wo); }
    virtual double pdf(const Vec3& wi, const Vec3& wo) const { return pdf(prepared(wi), wo); }
    BsdfEval evalPdf(const Vec3& wi, const Vec3& wo) const { return evalPdf(prepared(wi), wo); }
    BsdfSample sample(const Vec3& wi, const BsdfSampleInput& u, Rng& rng) const {
        return sample(prepared(wi), u, rng);
    }
    // With the generator bsdfSampleRng(u).
    BsdfSample sample(const Vec3& wi, const BsdfSampleInput& u) const {
        Rng rng = bsdfSampleRng(u);
        return sample(wi, u, rng);
    }
    // This BSDF with wi fixed.
    BsdfSlice slice(const Vec3& wi) const;
    // Bytes the BSDF holds (its parameters and tables), for memory reports.
    virtual size_t memoryBytes() const = 0;

  protected:
    Bsdf() = default;
    Bsdf(const Bsdf&) = default;
    Bsdf& operator=(const Bsdf&) = default;

  private:
    BsdfIncident prepared(const Vec3& wi) const {
        BsdfIncident in;
        prepare(wi, in);
        return in;
    }
};

// A Bsdf with wi fixed: what depends on wi is computed once, at construction.
// Its results equal the Bsdf's (wi, wo) forms. Holds a pointer: the Bsdf must
// outlive it.
class BsdfSlice {
  public:
    BsdfSlice() = default;
    BsdfSlice(const Bsdf& bsdf, const Vec3& wi) : bsdf_(&bsdf) { bsdf.prepare(wi, in_); }
    // With the importance of each channel (BsdfIncident::setImportance).
    BsdfSlice(const Bsdf& bsdf, const Vec3& wi, const Rgb& importance) : bsdf_(&bsdf) {
        in_.setImportance(importance);
        bsdf.prepare(wi, in_);
    }

    const Vec3& wi() const { return in_.wi(); }
    const Bsdf& bsdf() const { return *bsdf_; }
    const BsdfIncident& incident() const { return in_; }

    Rgb eval(const Vec3& wo) const { return bsdf_->eval(in_, wo); }
    double pdf(const Vec3& wo) const { return bsdf_->pdf(in_, wo); }
    BsdfEval evalPdf(const Vec3& wo) const { return bsdf_->evalPdf(in_, wo); }
    BsdfSample sample(const BsdfSampleInput& u, Rng& rng) const {
        return bsdf_->sample(in_, u, rng);
    }
    BsdfSample sample(const BsdfSampleInput& u) const {
        Rng rng = bsdfSampleRng(u);
        return sample(u, rng);
    }

  private:
    const Bsdf* bsdf_ = nullptr;
    BsdfIncident in_;
};

inline BsdfSlice Bsdf::slice(const Vec3& wi) const { return BsdfSlice(*this, wi); }

// A BSDF whose multiply scattered ("spread") part leaves the surface at
// another point than the one the light entered, as a BSSRDF's does (the
// yarn model with exit offsets, issue 47, docs/exit-point.md). The path
// tracer splits such an event (render/path_tracer.h):
//   - an exit point at every event: sampleOffset gives the offset (along
//     the tube dz radii, around it dpsi radians, tube_accel.h exitPoint)
//     and a weight per channel (the offset density's channel MIS);
//   - next-event estimation at the hit with evalSurface, and at the exit
//     point, in its own frame, with evalSpread times the offset weight;
//   - sampleEvent's one continuation: the surface part's from the hit, or
//     the spread part's from the exit point (times the offset weight).
// evalSurface's and evalSpread's densities are those with which
// sampleEvent reaches wo from the hit and from the exit point, so MIS
// between next-event estimation and BSDF sampling holds at either point.
// Every call takes an incident this BSDF prepared, with wi at the hit.
struct SpreadOffset {
    double dz = 0, dpsi = 0;  // the exit offset (tube radii, radians)
    Rgb weight;               // per channel, to multiply the spread part by
};

struct SpreadSample {
    bool spread = false;  // the path continues from the exit point
    BsdfSample sample;    // wo in the frame of where it continues from
};

class ExitSpread {
  public:
    virtual ~ExitSpread() = default;
    // Whether the event at `in` splits; where not, the BSDF's eval, pdf and
    // sample hold as they are.
    virtual bool splits(const BsdfIncident& in) const = 0;
    // The exit offset from three uniform numbers (the channel, the offset).
    virtual SpreadOffset sampleOffset(const BsdfIncident& in, const BsdfSampleInput& u) const = 0;
    // The surface part at wo (the hit's frame), and sampleEvent's density of
    // reaching wo from the hit.
    virtual BsdfEval evalSurface(const BsdfIncident& in, const Vec3& wo) const = 0;
    // The spread part at wo (the exit point's frame), and sampleEvent's
    // density of reaching wo from the exit point.
    virtual BsdfEval evalSpread(const BsdfIncident& in, const Vec3& woExit) const = 0;
    // The continuation: `u` as for Bsdf::sample; weight = that part's value
    // over its density (a delta's weight for the T lobe).
    virtual SpreadSample sampleEvent(const BsdfIncident& in, const BsdfSampleInput& u,
                                     Rng& rng) const = 0;
    // The last three for many incidents (as Bsdf's batches): out[k] is the
    // single call's for query k, bit for bit.
    virtual void evalSurfaceBatch(const BsdfIncident* const* in, const Vec3* wo, size_t count,
                                  BsdfEval* out) const {
        for (size_t k = 0; k < count; ++k) out[k] = evalSurface(*in[k], wo[k]);
    }
    virtual void evalSpreadBatch(const BsdfIncident* const* in, const Vec3* woExit, size_t count,
                                 BsdfEval* out) const {
        for (size_t k = 0; k < count; ++k) out[k] = evalSpread(*in[k], woExit[k]);
    }
    virtual void sampleEventBatch(const BsdfIncident* const* in, const BsdfSampleInput* u,
                                  Rng* const* rng, size_t count, SpreadSample* out) const {
        for (size_t k = 0; k < count; ++k) out[k] = sampleEvent(*in[k], u[k], *rng[k]);
    }
};

}  // namespace weft
