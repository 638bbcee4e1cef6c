#pragma once
// A camera that replays frames made before streaming starts (rendered by the
// simulator or read from files), like librealsense's software device: the
// code above the HAL cannot tell it from a sensor, and delivering a frame
// costs nothing, so a stream or benchmark driven by it measures the pipeline
// above the HAL alone.
//
// It behaves as a free-running sensor: frame n is delivered at start + n *
// interval, and frames whose time passed while nobody called capture() are
// skipped (their sequence numbers are missing), as a real sensor overwrites
// them. Interval 0 delivers a frame at every capture() at once.

#include "hal/camera.hpp"
#include "hal/sim/sim_world.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace stria::hal::sim {

class ReplayCamera final : public Camera {
public:
    // frames: CV_8UC3 (BGR), at least one, all of one size; replayed in order, looped.
    static Result<std::unique_ptr<ReplayCamera>> create(std::vector<cv::Mat> frames, std::int64_t frameIntervalNs);

    const char* backendName() const override { return "replay"; }
    // The frames are already made: only the size is checked; exposure and gain
    // are reported as configured.
    Status configure(const CameraConfig& config) override;
    Status start() override;
    void stop() override;
    Result<CapturedFrame> capture(std::chrono::milliseconds timeout) override;

    int frameCount() const { return static_cast<int>(frames_.size()); }

private:
    ReplayCamera(std::vector<cv::Mat> frames, std::int64_t frameIntervalNs) :
        frames_(std::move(frames)), frameIntervalNs_(frameIntervalNs)
    {
    }

    std::vector<cv::Mat> frames_;
    std::int64_t frameIntervalNs_;
    CameraConfig config_;
    bool configured_ = false;
    bool started_ = false;
    std::int64_t epochNs_ = 0;
    std::uint64_t nextFrame_ = 0;
};

// `count` lit frames of the world's scene as the simulated camera would see
// them at this exposure and gain, each with its own noise (seeds seed,
// seed + 1, ...), so a replay loop does not show the decoder one frame only.
Result<std::vector<cv::Mat>> renderReplayFrames(const SimWorld& world, int count, double exposureUs,
                                                double analogueGain);

}  // namespace stria::hal::sim
