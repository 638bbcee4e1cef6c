#include "hal/libcamera/libcamera_camera.hpp"

#include "hal/libcamera/compat.hpp"

#include <libcamera/libcamera.h>

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace stria::hal {
namespace {

using namespace libcamera;

std::string sizeName(const Size& size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

std::shared_ptr<libcamera::Camera> findCamera(CameraManager& manager, const std::string& spec)
{
    const auto cameras = manager.cameras();
    if (spec.empty()) return cameras.front();
    if (std::all_of(spec.begin(), spec.end(), [](char c) { return c >= '0' && c <= '9'; })) {
        const std::size_t index = std::stoul(spec);
        return index < cameras.size() ? cameras[index] : nullptr;
    }
    return manager.get(spec);
}

}  // namespace

bool exposureMatches(double requestedUs, double appliedUs)
{
    return std::abs(appliedUs - requestedUs) <= std::max(0.02 * requestedUs, 100.0);
}

LibcameraCamera::LibcameraCamera(std::unique_ptr<CameraManager> manager, std::shared_ptr<libcamera::Camera> camera)
    : manager_(std::move(manager)), camera_(std::move(camera))
{
    camera_->requestCompleted.connect(this, &LibcameraCamera::requestComplete);
}

LibcameraCamera::~LibcameraCamera()
{
    stop();
    release();
    camera_->requestCompleted.disconnect(this);
    camera_->release();
    camera_.reset();
}

Result<std::unique_ptr<LibcameraCamera>> LibcameraCamera::open(const std::string& spec)
{
    auto manager = std::make_unique<CameraManager>();
    if (int ret = manager->start(); ret < 0)
        return Status::error(std::string("libcamera: cannot start the camera manager: ") + std::strerror(-ret));
    const auto cameras = manager->cameras();
    if (cameras.empty())
        return Status::error("no libcamera camera found (check the sensor's dtoverlay in config.txt; `cam --list` "
                             "shows what libcamera sees)");
    std::shared_ptr<libcamera::Camera> camera = findCamera(*manager, spec);
    if (!camera) {
        std::string ids;
        for (std::size_t i = 0; i < cameras.size(); ++i)
            ids += (i ? ", " : "") + std::to_string(i) + ": " + cameras[i]->id();
        return Status::error("libcamera camera '" + spec + "' not found (cameras: " + ids + ")");
    }
    if (int ret = camera->acquire(); ret < 0)
        return Status::error("libcamera camera '" + camera->id() + "': cannot acquire: " + std::strerror(-ret) +
                             (ret == -EBUSY ? " (another program is using the camera)" : ""));
    return std::unique_ptr<LibcameraCamera>(new LibcameraCamera(std::move(manager), std::move(camera)));
}

Status LibcameraCamera::error(const std::string& what) const
{
    return Status::error("libcamera camera '" + camera_->id() + "': " + what);
}

Status LibcameraCamera::configure(const CameraConfig& config)
{
    stop();
    release();
    cameraConfig_ = camera_->generateConfiguration({StreamRole::StillCapture});
    if (!cameraConfig_ || cameraConfig_->size() != 1) return error("cannot generate a still-capture configuration");
    StreamConfiguration& streamConfig = cameraConfig_->at(0);
    const Size requested(unsigned(config.width), unsigned(config.height));
    streamConfig.pixelFormat = formats::RGB888;  // bytes B, G, R
    streamConfig.size = requested;
    streamConfig.bufferCount = unsigned(std::max(config.bufferCount, 2));
    compat::setIdentityOrientation(*cameraConfig_);
    if (cameraConfig_->validate() == CameraConfiguration::Invalid)
        return error("RGB888 " + sizeName(requested) + " is not a valid configuration");
    if (streamConfig.size != requested)
        return error("delivers " + sizeName(streamConfig.size) + " when asked for " + sizeName(requested));
    if (streamConfig.pixelFormat != formats::RGB888)
        return error("cannot deliver RGB888 (offers " + streamConfig.pixelFormat.toString() + ")");
    if (!compat::isIdentityOrientation(*cameraConfig_)) return error("cannot deliver unflipped frames");
    if (int ret = camera_->configure(cameraConfig_.get()); ret < 0)
        return error(std::string("cannot configure: ") + std::strerror(-ret));

    stream_ = streamConfig.stream();
    stride_ = int(streamConfig.stride);
    allocator_ = std::make_unique<FrameBufferAllocator>(camera_);
    if (int ret = allocator_->allocate(stream_); ret < 0)
        return error(std::string("cannot allocate buffers: ") + std::strerror(-ret));
    for (const std::unique_ptr<FrameBuffer>& buffer : allocator_->buffers(stream_)) {
        // Buffers are mapped once, whole (planes may share one dmabuf).
        const FrameBuffer::Plane& plane = buffer->planes().front();
        const off_t dmabufLength = ::lseek(plane.fd.get(), 0, SEEK_END);
        const std::size_t frameBytes = std::size_t(stride_) * requested.height;
        if (dmabufLength < 0 || std::size_t(plane.offset) + plane.length > std::size_t(dmabufLength) ||
            plane.length < frameBytes) {
            release();
            return error("buffer plane does not hold a " + sizeName(requested) + " frame");
        }
        void* base = ::mmap(nullptr, std::size_t(dmabufLength), PROT_READ, MAP_SHARED, plane.fd.get(), 0);
        if (base == MAP_FAILED) {
            const int err = errno;
            release();
            return error(std::string("cannot map a buffer: ") + std::strerror(err));
        }
        auto* bytes = static_cast<std::uint8_t*>(base);
        mappings_.push_back({bytes, std::size_t(dmabufLength), bytes + plane.offset});

        std::unique_ptr<Request> request = camera_->createRequest(requests_.size());
        if (!request || request->addBuffer(stream_, buffer.get()) < 0) {
            release();
            return error("cannot create a request");
        }
        requests_.push_back(std::move(request));
    }
    completed_.reserve(requests_.size());
    config_ = config;
    return Status::ok();
}

void LibcameraCamera::release()
{
    for (const Mapping& mapping : mappings_) ::munmap(mapping.base, mapping.length);
    mappings_.clear();
    requests_.clear();
    allocator_.reset();
    cameraConfig_.reset();
    stream_ = nullptr;
}

Status LibcameraCamera::queue(Request* request)
{
    // Every request carries the manual settings, so nothing can drift back to auto.
    compat::setManualExposure(request->controls(), config_.exposureUs, config_.analogueGain);
    if (int ret = camera_->queueRequest(request); ret < 0)
        return error(std::string("cannot queue a request: ") + std::strerror(-ret));
    return Status::ok();
}

Status LibcameraCamera::start()
{
    if (requests_.empty()) return error("start() before configure()");
    if (running_) return Status::ok();
    ControlList controls(controls::controls);
    compat::setManualExposure(controls, config_.exposureUs, config_.analogueGain);
    if (int ret = camera_->start(&controls); ret < 0) return error(std::string("cannot start: ") + std::strerror(-ret));
    running_ = true;
    for (const std::unique_ptr<Request>& request : requests_) {
        request->reuse(Request::ReuseBuffers);
        if (Status s = queue(request.get()); !s) {
            stop();
            return s;
        }
    }
    return Status::ok();
}

void LibcameraCamera::stop()
{
    if (!running_) return;
    camera_->stop();  // completes (cancels) every queued request before returning
    std::lock_guard lock(mutex_);
    completed_.clear();
    lent_ = nullptr;
    running_ = false;
}

void LibcameraCamera::requestComplete(Request* request)
{
    {
        std::lock_guard lock(mutex_);
        completed_.push_back(request);
    }
    completedChanged_.notify_one();
}

Result<CapturedFrame> LibcameraCamera::capture(std::chrono::milliseconds timeout)
{
    if (!running_) return error("capture() before start()");
    if (lent_) {
        Request* previous = std::exchange(lent_, nullptr);
        previous->reuse(Request::ReuseBuffers);
        if (Status s = queue(previous); !s) return s;
    }
    const auto deadline =
        std::chrono::steady_clock::now() + std::min(timeout, std::chrono::milliseconds(std::int64_t{1} << 40));
    double lastExposureUs = 0;
    for (int frames = 0; frames < kMaxSettleFrames; ++frames) {
        Request* request;
        {
            std::unique_lock lock(mutex_);
            if (!completedChanged_.wait_until(lock, deadline, [this] { return !completed_.empty(); }))
                return error("no frame within " + std::to_string(timeout.count()) + " ms");
            request = completed_.front();
            completed_.erase(completed_.begin());
        }
        if (request->status() != Request::RequestComplete) return error("request cancelled (camera disconnected?)");
        const compat::AppliedExposure applied = compat::appliedExposure(request->metadata());
        if (applied.exposureUs && !exposureMatches(config_.exposureUs, *applied.exposureUs)) {
            // The sensor applies new settings a few frames late.
            lastExposureUs = *applied.exposureUs;
            request->reuse(Request::ReuseBuffers);
            if (Status s = queue(request); !s) return s;
            continue;
        }
        const FrameBuffer* buffer = request->buffers().begin()->second;
        lent_ = request;
        CapturedFrame frame;
        frame.view = FrameView{mappings_[request->cookie()].pixels, config_.width, config_.height, stride_,
                               PixelFormat::Bgr8};
        frame.sequence = buffer->metadata().sequence;
        frame.exposureUs = applied.exposureUs.value_or(0.0);
        // Pipelines stamp the start of readout of the first row (Raspberry
        // Pi: unicam's start of frame), which ends that row's exposure. Erring
        // early makes the scan loop drop a frame rather than accept one
        // exposed partly before the LED was on.
        const std::int64_t stampNs = applied.sensorTimestampNs.value_or(std::int64_t(buffer->metadata().timestamp));
        frame.timestampNs = stampNs - std::int64_t(applied.exposureUs.value_or(config_.exposureUs) * 1000);
        frame.analogueGain = applied.analogueGain.value_or(0.0);
        return frame;
    }
    return error("exposure still " + std::to_string(std::lround(lastExposureUs)) + " us after " +
                 std::to_string(kMaxSettleFrames) + " frames, asked for " +
                 std::to_string(std::lround(config_.exposureUs)) + " us");
}

}  // namespace stria::hal
