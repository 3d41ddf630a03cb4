// weft/core/embree.h — RAII ownership of an Embree 3 device, and ray set-up.
//
// The device reports errors through a callback that turns them into
// exceptions at the next check(), and counts the bytes Embree allocates
// (memory monitor), so that geometry + BVH memory can be reported (as Embree
// recommends). initRay fills every field of a ray the same way for the gather's
// ply tracer and the renderer's tube accelerator.
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <string>

#include "weft/core/vec.h"

namespace weft {

class EmbreeDevice {
  public:
    EmbreeDevice();
    ~EmbreeDevice();
    EmbreeDevice(const EmbreeDevice&) = delete;
    EmbreeDevice& operator=(const EmbreeDevice&) = delete;

    RTCDevice get() const { return device_; }
    // Throws std::runtime_error if Embree reported an error since the last check.
    void check(const char* what) const;
    // Bytes currently allocated by Embree (geometry buffers + acceleration structures).
    int64_t allocatedBytes() const { return allocated_.load(); }
    // Largest value allocatedBytes() has had.
    int64_t peakBytes() const { return peak_.load(); }

    static std::string version();

  private:
    static void errorCallback(void* user, RTCError code, const char* message);
    static bool memoryCallback(void* user, ssize_t bytes, bool post);

    RTCDevice device_ = nullptr;
    mutable std::atomic<int> lastError_{RTC_ERROR_NONE};
    mutable std::string lastMessage_;
    std::atomic<int64_t> allocated_{0}, peak_{0};
};

// Every field of an Embree ray: origin and direction rounded to float, tnear
// 0, tfar = min(tMax, 1e30) (Embree's rays are float), time 0, every mask
// bit, id 0, no flags.
inline void initRay(RTCRay& ray, const Vec3& org, const Vec3& dir, double tMax) {
    ray.org_x = static_cast<float>(org.x);
    ray.org_y = static_cast<float>(org.y);
    ray.org_z = static_cast<float>(org.z);
    ray.dir_x = static_cast<float>(dir.x);
    ray.dir_y = static_cast<float>(dir.y);
    ray.dir_z = static_cast<float>(dir.z);
    ray.tnear = 0.0f;
    ray.tfar = static_cast<float>(std::min(tMax, 1e30));
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
}

// The same for an intersection query, with no hit yet (geomID, primID and
// instID[0] invalid).
inline void initRay(RTCRayHit& rayHit, const Vec3& org, const Vec3& dir, double tMax) {
    initRay(rayHit.ray, org, dir, tMax);
    rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayHit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rayHit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

}  // namespace weft
