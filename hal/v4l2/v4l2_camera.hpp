#pragma once
// Camera backend for USB/UVC cameras (endoscope heads) through raw V4L2
// ioctls and mmap streaming. The device's uncompressed format is converted
// into a BGR buffer allocated in configure(); compressed-only cameras are
// refused because JPEG artefacts smear exactly the stripe edges we decode.

#include "hal/camera.hpp"
#include "hal/v4l2/v4l2_device.hpp"

#include <linux/videodev2.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace stria::hal {

class V4l2Camera final : public Camera {
public:
    // Opens the node, checks it can capture and stream, and picks BGR24,
    // RGB24 or YUYV (in that order of preference).
    static Result<std::unique_ptr<V4l2Camera>> open(const std::string& path);
    static Result<std::unique_ptr<V4l2Camera>> open(std::unique_ptr<V4l2Device> device);
    ~V4l2Camera() override;

    const char* backendName() const override { return "v4l2"; }
    Status configure(const CameraConfig& config) override;
    Status start() override;
    void stop() override;
    Result<CapturedFrame> capture(std::chrono::milliseconds timeout) override;

    std::uint32_t pixelFormat() const { return pixelFormat_; }  // V4L2 fourcc picked by open()
    // Controls the camera lacks (e.g. "gain"), filled by configure(): the
    // frame is then taken with the camera's own setting for them.
    std::vector<std::string> missingControls() const override { return missingControls_; }

private:
    struct Buffer {
        void* address = nullptr;
        std::size_t length = 0;
    };

    V4l2Camera(std::unique_ptr<V4l2Device> device, std::uint32_t pixelFormat);
    Status error(const std::string& what, int negativeErrno) const;
    Status setFormat(const CameraConfig& config);
    Status setControls(const CameraConfig& config);
    // Sets a control if the camera has it: ok and *applied = value read back;
    // a missing control is recorded in missingControls_ and is not an error.
    Status setControl(std::uint32_t id, const char* name, std::int32_t value, std::int32_t* applied);
    Status mapBuffers(int count);
    void releaseBuffers();
    // CLOCK_MONOTONIC start of exposure of the first row (UVC stamps the
    // start of exposure; other drivers the end of the frame).
    std::int64_t exposureStartNs(const v4l2_buffer& buffer) const;

    std::unique_ptr<V4l2Device> device_;
    std::uint32_t pixelFormat_;
    std::vector<Buffer> buffers_;
    std::vector<std::uint8_t> bgr_;
    std::vector<std::string> missingControls_;
    int width_ = 0, height_ = 0;
    std::uint32_t bytesPerLine_ = 0, imageBytes_ = 0;
    std::int64_t frameIntervalNs_ = 0;
    double exposureUs_ = 0, analogueGain_ = 0;
    bool streaming_ = false;
};

}  // namespace stria::hal
