#pragma once
// The camera interface. One frame per scan: exposure and gain are fixed (no
// auto exposure or white balance while scanning) so the stripe colours the
// decoder sees depend on the scene, not on a control loop.

#include "pipeline/frame.hpp"
#include "pipeline/status.hpp"

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace stria::hal {

struct CameraConfig {
    int width = 0, height = 0;          // must be delivered exactly (else configure() fails naming both sizes)
    double exposureUs = 10000;          // fixed exposure time; no auto exposure / white balance during a scan
    double analogueGain = 1.0;
    int bufferCount = 3;
};

struct CapturedFrame {
    FrameView view;                     // BGR8, borrowed from the camera's buffers (mapped/allocated in
                                        // configure()); valid until the next capture() or stop()
    std::uint64_t sequence = 0;
    std::int64_t timestampNs = 0;       // CLOCK_MONOTONIC, start of exposure
    double exposureUs = 0, analogueGain = 0;  // as actually applied (from metadata where the backend has it)
};

class Camera {
public:
    virtual ~Camera() = default;
    virtual const char* backendName() const = 0;  // "sim", "v4l2", "libcamera"
    virtual Status configure(const CameraConfig& config) = 0;
    virtual Status start() = 0;
    virtual void stop() = 0;
    // Waits at most `timeout` for the next frame. Timeout -> error "camera '<dev>': no frame within N ms".
    virtual Result<CapturedFrame> capture(std::chrono::milliseconds timeout) = 0;
    // Controls the device lacks (e.g. a UVC camera without manual exposure),
    // known after configure(). Backends that can set everything keep the default.
    virtual std::vector<std::string> missingControls() const { return {}; }
};

}  // namespace stria::hal
