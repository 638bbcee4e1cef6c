#pragma once
// Camera backend for CSI sensors through libcamera (Raspberry Pi CM4/Pi 5
// heads). The still-capture stream is asked for libcamera's RGB888, whose
// bytes in memory are B, G, R (DRM fourcc naming, little endian): exactly the
// decoder's BGR8, so frames are used in place, without a copy.
//
// Buffers are allocated and mapped once in configure(); requests are reused.
// libcamera completes requests in its own thread: the handler only posts them
// to a queue that capture() waits on.

#include "hal/camera.hpp"

#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace libcamera {
class Camera;
class CameraConfiguration;
class CameraManager;
class FrameBufferAllocator;
class Request;
class Stream;
}  // namespace libcamera

namespace stria::hal {

// Sensors quantise the exposure time to whole lines (10-40 us), so a frame
// counts as taken with the requested exposure within 2 % or 100 us.
bool exposureMatches(double requestedUs, double appliedUs);

class LibcameraCamera final : public Camera {
public:
    // How many frames capture() waits for the exposure to take effect.
    static constexpr int kMaxSettleFrames = 8;

    // `camera` is a libcamera id, an index ("0"), or empty for the first camera.
    static Result<std::unique_ptr<LibcameraCamera>> open(const std::string& camera);
    ~LibcameraCamera() override;

    const char* backendName() const override { return "libcamera"; }
    Status configure(const CameraConfig& config) override;
    Status start() override;
    void stop() override;
    Result<CapturedFrame> capture(std::chrono::milliseconds timeout) override;

private:
    struct Mapping {
        std::uint8_t* base = nullptr;
        std::size_t length = 0;
        std::uint8_t* pixels = nullptr;  // base + plane offset
    };

    LibcameraCamera(std::unique_ptr<libcamera::CameraManager> manager, std::shared_ptr<libcamera::Camera> camera);
    Status error(const std::string& what) const;
    void requestComplete(libcamera::Request* request);  // libcamera's thread
    Status queue(libcamera::Request* request);
    void release();

    // Declared first: the manager must outlive the camera it owns.
    std::unique_ptr<libcamera::CameraManager> manager_;
    std::shared_ptr<libcamera::Camera> camera_;
    std::unique_ptr<libcamera::CameraConfiguration> cameraConfig_;
    std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
    libcamera::Stream* stream_ = nullptr;
    std::vector<std::unique_ptr<libcamera::Request>> requests_;
    std::vector<Mapping> mappings_;  // per request (cookie = index)
    CameraConfig config_;
    int stride_ = 0;
    bool running_ = false;
    libcamera::Request* lent_ = nullptr;  // its buffer backs the last CapturedFrame

    std::mutex mutex_;
    std::condition_variable completedChanged_;
    std::vector<libcamera::Request*> completed_;  // capacity reserved in configure()
};

}  // namespace stria::hal
