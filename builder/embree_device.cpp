#include "builder/embree_device.hpp"

#include <spdlog/spdlog.h>

namespace shadowtiles {
namespace {

void log_embree_error(void*, RTCError code, const char* message) {
  spdlog::error("embree error {}: {}", int(code), message ? message : "");
}

}  // namespace

Result<EmbreeDevice> EmbreeDevice::create() {
  RTCDevice device = rtcNewDevice(nullptr);
  if (!device)
    return make_error(ErrorCode::io_error, "embree: rtcNewDevice failed (error " +
                                               std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
  rtcSetDeviceErrorFunction(device, log_embree_error, nullptr);
  return EmbreeDevice(device);
}

EmbreeDevice::~EmbreeDevice() {
  if (device_) rtcReleaseDevice(device_);
}

}  // namespace shadowtiles
