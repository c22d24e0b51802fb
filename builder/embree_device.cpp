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

std::string EmbreeDevice::version() const {
  auto part = [&](RTCDeviceProperty p) { return std::to_string(rtcGetDeviceProperty(device_, p)); };
  return part(RTC_DEVICE_PROPERTY_VERSION_MAJOR) + "." + part(RTC_DEVICE_PROPERTY_VERSION_MINOR) + "." +
         part(RTC_DEVICE_PROPERTY_VERSION_PATCH);
}

int EmbreeDevice::native_ray_packet() const {
  if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)) return 16;
  if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED)) return 8;
  if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED)) return 4;
  return 1;
}

EmbreeDevice::~EmbreeDevice() {
  if (device_) rtcReleaseDevice(device_);
}

}  // namespace shadowtiles
