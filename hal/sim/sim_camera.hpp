#pragma once
// The simulated camera: a free-running sensor that starts a frame every frame
// interval and renders the SimWorld's scene for it, with the projector lit
// only if the LED was on for the whole exposure. A partly lit exposure counts
// as unlit: the worst case, so firmware that captures too early is caught.
//
// Brightness follows exposure time and gain: the scene's RenderSettings are
// the look at 10 ms and gain 1. The scene is static and the noise seed fixed,
// so the lit and the dark frame are each rendered once per configure() and
// reused: an honest shortcut that keeps 1000-scan tests fast.

#include "hal/camera.hpp"
#include "hal/sim/sim_world.hpp"

#include <cstdint>

namespace stria::hal::sim {

class SimCamera final : public Camera {
public:
    static constexpr double kNominalExposureUs = 10000;

    SimCamera(SimWorld& world, int frameIntervalUs);

    const char* backendName() const override { return "sim"; }
    Status configure(const CameraConfig& config) override;
    Status start() override;
    void stop() override;
    Result<CapturedFrame> capture(std::chrono::milliseconds timeout) override;

    // Frames rendered so far (a test checks the cache works).
    int renderCount() const { return renderCount_; }

private:
    Status renderInto(bool projectorOn, Rendering& out, bool& valid);

    SimWorld& world_;
    SceneRenderer renderer_;
    std::int64_t frameIntervalNs_;
    CameraConfig config_;
    RenderSettings settings_;
    bool configured_ = false;
    bool started_ = false;
    std::int64_t epochNs_ = 0;
    std::uint64_t nextFrame_ = 0;
    Rendering lit_, dark_;
    bool litValid_ = false, darkValid_ = false;
    int renderCount_ = 0;
};

}  // namespace stria::hal::sim
