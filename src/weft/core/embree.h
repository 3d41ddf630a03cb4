// weft/core/embree.h — RAII ownership of an Embree 3 device.
//
// The device reports errors through a callback that turns them into
// exceptions at the next check(), and counts the bytes Embree allocates
// (memory monitor), so that geometry + BVH memory can be reported (STYLE.md:
// Embree).
#pragma once

#include <embree3/rtcore.h>

#include <atomic>
#include <cstdint>
#include <string>

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

}  // namespace weft
