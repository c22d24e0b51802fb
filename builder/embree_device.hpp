// EmbreeDevice: RAII owner of one Embree device, shared by every tile renderer of a build.
// Embree errors are routed to the log. Thread safety: an RTCDevice is thread-safe; scenes built
// from it may be built and traced concurrently on different threads.
#pragma once

#include <string>

#include <embree3/rtcore.h>

#include "common/result.hpp"

namespace shadowtiles {

class EmbreeDevice {
 public:
  static Result<EmbreeDevice> create();
  EmbreeDevice(EmbreeDevice&& other) noexcept : device_(other.device_) { other.device_ = nullptr; }
  EmbreeDevice& operator=(EmbreeDevice&&) = delete;
  EmbreeDevice(const EmbreeDevice&) = delete;
  ~EmbreeDevice();
  RTCDevice get() const { return device_; }
  // What Embree runs on this host, for a build's record: its version ("3.13.5") and the widest ray
  // packet its kernels trace natively (16: AVX-512, 8: AVX/AVX2, 4: SSE). Ray-casting rates, and so
  // the build-time ratio, depend on it (docs/build-time.md, session 39).
  std::string version() const;
  int native_ray_packet() const;

 private:
  explicit EmbreeDevice(RTCDevice device) : device_(device) {}
  RTCDevice device_ = nullptr;
};

// RAII for an RTCScene.
class EmbreeScene {
 public:
  explicit EmbreeScene(RTCScene scene) : scene_(scene) {}
  EmbreeScene(EmbreeScene&& other) noexcept : scene_(other.scene_) { other.scene_ = nullptr; }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;
  EmbreeScene& operator=(EmbreeScene&&) = delete;
  ~EmbreeScene() {
    if (scene_) rtcReleaseScene(scene_);
  }
  RTCScene get() const { return scene_; }

 private:
  RTCScene scene_ = nullptr;
};

}  // namespace shadowtiles
