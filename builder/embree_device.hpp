// EmbreeDevice: RAII owner of one Embree device, shared by every tile renderer of a build.
// Embree errors are routed to the log. Thread safety: an RTCDevice is thread-safe; scenes built
// from it may be built and traced concurrently on different threads.
#pragma once

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
