#pragma once
// The simulated world shared by SimCamera, SimLight and SimButton (like
// ArduPilot's SITL): the light writes the LED state into it, the camera reads
// that state for the interval it exposes, so an LED switched on too late gives
// a frame without stripes. Times are CLOCK_MONOTONIC nanoseconds.

#include "hal/sim/scene/scene.hpp"

#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

namespace stria::hal::sim {

struct LedEvent {
    std::int64_t timeNs = 0;
    bool on = false;
};

class SimWorld {
public:
    SimWorld(SimRig rig, Scene scene, RenderSettings render) :
        rig_(std::move(rig)), scene_(std::move(scene)), render_(render)
    {
    }
    SimWorld(const SimWorld&) = delete;
    SimWorld& operator=(const SimWorld&) = delete;

    const SimRig& rig() const { return rig_; }
    const Scene& scene() const { return scene_; }
    const RenderSettings& renderSettings() const { return render_; }

    // Sets the LED and logs the change with its time. Lock-free and
    // allocation-free, so SimLight::set() stays async-signal-safe.
    void setLed(bool on);
    bool ledOn() const { return led_.load(); }
    // The most recent changes (at most kLogCapacity), oldest first.
    std::vector<LedEvent> ledLog() const;
    // True if the LED was on during the whole of [beginNs, endNs].
    bool ledOnThroughout(std::int64_t beginNs, std::int64_t endNs) const;

    // Fault injection: the next `count` captures time out.
    void injectCaptureTimeouts(int count) { captureTimeouts_.fetch_add(count); }
    bool takeCaptureTimeout();

    static constexpr std::size_t kLogCapacity = 4096;

private:
    SimRig rig_;
    Scene scene_;
    RenderSettings render_;
    std::atomic<bool> led_{false};
    // Ring of changes, each packed as timeNs * 2 + on so one atomic holds it.
    std::array<std::atomic<std::int64_t>, kLogCapacity> log_{};
    std::atomic<std::uint64_t> logCount_{0};
    std::atomic<int> captureTimeouts_{0};
};

}  // namespace stria::hal::sim
