#include "weft/core/embree.h"

#include <stdexcept>

namespace weft {

EmbreeDevice::EmbreeDevice() {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("Embree: cannot create a device");
    rtcSetDeviceErrorFunction(device_, &EmbreeDevice::errorCallback, this);
    rtcSetDeviceMemoryMonitorFunction(device_, &EmbreeDevice::memoryCallback, this);
}

EmbreeDevice::~EmbreeDevice() {
    if (device_) rtcReleaseDevice(device_);
}

void EmbreeDevice::errorCallback(void* user, RTCError code, const char* message) {
    auto* self = static_cast<EmbreeDevice*>(user);
    self->lastMessage_ = message ? message : "";
    self->lastError_.store(code);
}

bool EmbreeDevice::memoryCallback(void* user, ssize_t bytes, bool) {
    auto* self = static_cast<EmbreeDevice*>(user);
    const int64_t now = self->allocated_.fetch_add(bytes) + bytes;
    int64_t peak = self->peak_.load();
    while (now > peak && !self->peak_.compare_exchange_weak(peak, now)) {
    }
    return true;
}

void EmbreeDevice::check(const char* what) const {
    const int code = lastError_.exchange(RTC_ERROR_NONE);
    if (code != RTC_ERROR_NONE)
        throw std::runtime_error(std::string("Embree error while ") + what + ": " + lastMessage_ +
                                 " (code " + std::to_string(code) + ")");
}

std::string EmbreeDevice::version() { return RTC_VERSION_STRING; }

}  // namespace weft
