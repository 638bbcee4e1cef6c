#include "hal/v4l2/v4l2_camera.hpp"

#include "hal/v4l2/pixel_convert.hpp"

#include <linux/videodev2.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>

namespace stria::hal {
namespace {

std::string fourccName(std::uint32_t fourcc)
{
    std::string name;
    for (int i = 0; i < 4; ++i) {
        const char c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
        if (c != ' ' && c != '\0') name += c;
    }
    return name;
}

// Lower is better; formats we cannot use are absent.
int formatPreference(std::uint32_t fourcc)
{
    switch (fourcc) {
    case V4L2_PIX_FMT_BGR24: return 0;
    case V4L2_PIX_FMT_RGB24: return 1;
    case V4L2_PIX_FMT_YUYV: return 2;
    default: return -1;
    }
}

std::string join(const std::vector<std::string>& names)
{
    std::string out;
    for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
    return out;
}

}  // namespace

V4l2Camera::V4l2Camera(std::unique_ptr<V4l2Device> device, std::uint32_t pixelFormat)
    : device_(std::move(device)), pixelFormat_(pixelFormat)
{
}

V4l2Camera::~V4l2Camera()
{
    stop();
    releaseBuffers();
}

Result<std::unique_ptr<V4l2Camera>> V4l2Camera::open(const std::string& path)
{
    auto device = openV4l2Device(path);
    if (!device) return device.status();
    return open(std::move(*device));
}

Result<std::unique_ptr<V4l2Camera>> V4l2Camera::open(std::unique_ptr<V4l2Device> device)
{
    const std::string& path = device->path();
    v4l2_capability caps{};
    if (int ret = device->ioctl(VIDIOC_QUERYCAP, &caps); ret < 0)
        return Status::error(v4l2ErrorMessage(path, "not a V4L2 device (VIDIOC_QUERYCAP)", -ret));
    const std::uint32_t deviceCaps = (caps.capabilities & V4L2_CAP_DEVICE_CAPS) ? caps.device_caps : caps.capabilities;
    if (!(deviceCaps & V4L2_CAP_VIDEO_CAPTURE))
        return Status::error("camera '" + path + "' (" + reinterpret_cast<const char*>(caps.card) +
                             ") is not a video capture node (UVC cameras also expose a metadata node: use the "
                             "first /dev/videoN of the camera)");
    if (!(deviceCaps & V4L2_CAP_STREAMING))
        return Status::error("camera '" + path + "' cannot stream (no V4L2_CAP_STREAMING): stria needs mmap streaming");

    std::uint32_t best = 0;
    std::vector<std::string> offered, compressed;
    for (std::uint32_t index = 0;; ++index) {
        v4l2_fmtdesc desc{};
        desc.index = index;
        desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        if (int ret = device->ioctl(VIDIOC_ENUM_FMT, &desc); ret < 0) {
            if (ret == -EINVAL) break;  // end of the list
            return Status::error(v4l2ErrorMessage(path, "cannot list formats (VIDIOC_ENUM_FMT)", -ret));
        }
        offered.push_back(fourccName(desc.pixelformat));
        if (desc.flags & V4L2_FMT_FLAG_COMPRESSED) compressed.push_back(offered.back());
        const int preference = formatPreference(desc.pixelformat);
        if (preference >= 0 && (best == 0 || preference < formatPreference(best))) best = desc.pixelformat;
    }
    if (best == 0) {
        if (!offered.empty() && compressed.size() == offered.size())
            return Status::error("camera '" + path + "' offers only compressed formats (" + join(compressed) +
                                 "): stria needs YUYV, RGB24 or BGR24");
        return Status::error("camera '" + path + "' offers " + (offered.empty() ? "no formats" : join(offered)) +
                             ": stria needs YUYV, RGB24 or BGR24");
    }
    return std::unique_ptr<V4l2Camera>(new V4l2Camera(std::move(device), best));
}

Status V4l2Camera::error(const std::string& what, int negativeErrno) const
{
    return Status::error(v4l2ErrorMessage(device_->path(), what, -negativeErrno));
}

Status V4l2Camera::configure(const CameraConfig& config)
{
    stop();
    releaseBuffers();
    if (config.width <= 0 || config.height <= 0 || config.width % 2 != 0)
        return Status::error("camera '" + device_->path() + "': invalid size " + std::to_string(config.width) + "x" +
                             std::to_string(config.height) + " (width must be even and positive)");
    if (Status s = setFormat(config); !s) return s;
    if (Status s = setControls(config); !s) return s;
    if (Status s = mapBuffers(config.bufferCount); !s) {
        releaseBuffers();
        return s;
    }
    bgr_.assign(std::size_t(width_) * height_ * 3, 0);
    return Status::ok();
}

Status V4l2Camera::setFormat(const CameraConfig& config)
{
    v4l2_format format{};
    format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    format.fmt.pix.width = std::uint32_t(config.width);
    format.fmt.pix.height = std::uint32_t(config.height);
    format.fmt.pix.pixelformat = pixelFormat_;
    format.fmt.pix.field = V4L2_FIELD_NONE;
    if (int ret = device_->ioctl(VIDIOC_S_FMT, &format); ret < 0)
        return error("cannot set format " + fourccName(pixelFormat_) + " " + std::to_string(config.width) + "x" +
                         std::to_string(config.height) + " (VIDIOC_S_FMT)",
                     ret);
    // Drivers adjust instead of failing; a different size would silently
    // break the calibration, so it is refused.
    if (format.fmt.pix.width != std::uint32_t(config.width) || format.fmt.pix.height != std::uint32_t(config.height) ||
        format.fmt.pix.pixelformat != pixelFormat_)
        return Status::error("camera '" + device_->path() + "' delivers " + fourccName(format.fmt.pix.pixelformat) +
                             " " + std::to_string(format.fmt.pix.width) + "x" + std::to_string(format.fmt.pix.height) +
                             " when asked for " + fourccName(pixelFormat_) + " " + std::to_string(config.width) + "x" +
                             std::to_string(config.height) + ": pick a size the camera supports (v4l2-ctl --list-formats-ext)");
    // The frame period bounds the sensor readout (see exposureStartNs()).
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    const v4l2_fract& period = parm.parm.capture.timeperframe;
    const bool knowsPeriod = device_->ioctl(VIDIOC_G_PARM, &parm) == 0 && period.denominator > 0;
    frameIntervalNs_ = knowsPeriod ? std::int64_t(period.numerator) * 1'000'000'000 / period.denominator : 0;
    const std::uint32_t minLine = std::uint32_t(config.width) * (pixelFormat_ == V4L2_PIX_FMT_YUYV ? 2 : 3);
    width_ = config.width;
    height_ = config.height;
    bytesPerLine_ = std::max(format.fmt.pix.bytesperline, minLine);
    imageBytes_ = bytesPerLine_ * std::uint32_t(height_);
    return Status::ok();
}

Status V4l2Camera::setControl(std::uint32_t id, const char* name, std::int32_t value, std::int32_t* applied)
{
    v4l2_queryctrl query{};
    query.id = id;
    if (device_->ioctl(VIDIOC_QUERYCTRL, &query) < 0 || (query.flags & V4L2_CTRL_FLAG_DISABLED)) {
        missingControls_.push_back(name);
        return Status::ok();
    }
    if (value < query.minimum || value > query.maximum)
        return Status::error("camera '" + device_->path() + "': " + name + " " + std::to_string(value) +
                             " is outside the camera's range " + std::to_string(query.minimum) + ".." +
                             std::to_string(query.maximum));
    v4l2_control control{id, value};
    if (int ret = device_->ioctl(VIDIOC_S_CTRL, &control); ret < 0)
        return error(std::string("cannot set ") + name + " to " + std::to_string(value), ret);
    if (applied) {
        control = {id, 0};
        if (int ret = device_->ioctl(VIDIOC_G_CTRL, &control); ret < 0)
            return error(std::string("cannot read back ") + name, ret);
        *applied = control.value;
    }
    return Status::ok();
}

Status V4l2Camera::setControls(const CameraConfig& config)
{
    missingControls_.clear();
    // UVC ignores the exposure time while auto exposure is on, so it goes first.
    if (Status s = setControl(V4L2_CID_EXPOSURE_AUTO, "auto_exposure", V4L2_EXPOSURE_MANUAL, nullptr); !s) return s;
    if (Status s = setControl(V4L2_CID_AUTO_WHITE_BALANCE, "white_balance_automatic", 0, nullptr); !s) return s;

    // V4L2_CID_EXPOSURE_ABSOLUTE counts in units of 100 us.
    std::int32_t exposure = -1;
    const auto requested = static_cast<std::int32_t>(std::lround(config.exposureUs / 100.0));
    if (Status s = setControl(V4L2_CID_EXPOSURE_ABSOLUTE, "exposure_time_absolute", requested, &exposure); !s)
        return s;
    exposureUs_ = exposure >= 0 ? exposure * 100.0 : 0.0;

    // UVC gain has no unit: the camera's default value counts as 1.0x.
    v4l2_queryctrl query{};
    query.id = V4L2_CID_GAIN;
    const double unity = device_->ioctl(VIDIOC_QUERYCTRL, &query) == 0 ? std::max(query.default_value, 1) : 1;
    std::int32_t gain = -1;
    const auto gainValue = static_cast<std::int32_t>(std::lround(config.analogueGain * unity));
    if (Status s = setControl(V4L2_CID_GAIN, "gain", gainValue, &gain); !s) return s;
    analogueGain_ = gain >= 0 ? gain / unity : 0.0;
    return Status::ok();
}

Status V4l2Camera::mapBuffers(int count)
{
    v4l2_requestbuffers request{};
    request.count = std::uint32_t(std::max(count, 2));
    request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    request.memory = V4L2_MEMORY_MMAP;
    if (int ret = device_->ioctl(VIDIOC_REQBUFS, &request); ret < 0)
        return error("cannot allocate " + std::to_string(request.count) + " buffers (VIDIOC_REQBUFS)", ret);
    if (request.count < 2)
        return Status::error("camera '" + device_->path() + "' gave " + std::to_string(request.count) +
                             " buffers: streaming needs at least 2");
    for (std::uint32_t index = 0; index < request.count; ++index) {
        v4l2_buffer buffer{};
        buffer.index = index;
        buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        buffer.memory = V4L2_MEMORY_MMAP;
        if (int ret = device_->ioctl(VIDIOC_QUERYBUF, &buffer); ret < 0)
            return error("cannot query buffer " + std::to_string(index) + " (VIDIOC_QUERYBUF)", ret);
        if (buffer.length < imageBytes_)
            return Status::error("camera '" + device_->path() + "': buffer " + std::to_string(index) + " holds " +
                                 std::to_string(buffer.length) + " bytes, a frame needs " + std::to_string(imageBytes_));
        Buffer mapped{nullptr, buffer.length};
        if (int ret = device_->map(buffer.length, off_t(buffer.m.offset), &mapped.address); ret < 0)
            return error("cannot map buffer " + std::to_string(index), ret);
        buffers_.push_back(mapped);
    }
    return Status::ok();
}

void V4l2Camera::releaseBuffers()
{
    if (buffers_.empty()) return;
    for (const Buffer& buffer : buffers_) device_->unmap(buffer.address, buffer.length);
    buffers_.clear();
    v4l2_requestbuffers request{};
    request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    request.memory = V4L2_MEMORY_MMAP;
    device_->ioctl(VIDIOC_REQBUFS, &request);  // count 0 frees the driver's buffers
}

Status V4l2Camera::start()
{
    if (buffers_.empty()) return Status::error("camera '" + device_->path() + "': start() before configure()");
    if (streaming_) return Status::ok();
    for (std::uint32_t index = 0; index < buffers_.size(); ++index) {
        v4l2_buffer buffer{};
        buffer.index = index;
        buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        buffer.memory = V4L2_MEMORY_MMAP;
        if (int ret = device_->ioctl(VIDIOC_QBUF, &buffer); ret < 0)
            return error("cannot queue buffer " + std::to_string(index) + " (VIDIOC_QBUF)", ret);
    }
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (int ret = device_->ioctl(VIDIOC_STREAMON, &type); ret < 0) {
        device_->ioctl(VIDIOC_STREAMOFF, &type);  // takes back the queued buffers
        return error("cannot start streaming (VIDIOC_STREAMON)", ret);
    }
    streaming_ = true;
    return Status::ok();
}

void V4l2Camera::stop()
{
    if (!streaming_) return;
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    device_->ioctl(VIDIOC_STREAMOFF, &type);  // also dequeues every buffer
    streaming_ = false;
}

std::int64_t V4l2Camera::exposureStartNs(const v4l2_buffer& buffer) const
{
    const std::int64_t stampNs = std::int64_t(buffer.timestamp.tv_sec) * 1'000'000'000 + buffer.timestamp.tv_usec * 1000;
    if ((buffer.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) != V4L2_BUF_FLAG_TSTAMP_SRC_EOF) return stampNs;
    // Stamped when the last row arrived: the first row started exposing at
    // most one frame period (readout) plus the exposure earlier. Erring early
    // makes the scan loop drop a frame rather than accept one exposed partly
    // before the LED was on.
    return stampNs - frameIntervalNs_ - std::int64_t(exposureUs_ * 1000);
}

Result<CapturedFrame> V4l2Camera::capture(std::chrono::milliseconds timeout)
{
    if (!streaming_) return Status::error("camera '" + device_->path() + "': capture() before start()");
    using Clock = std::chrono::steady_clock;
    const Clock::time_point deadline = Clock::now() + std::min(timeout, std::chrono::milliseconds(std::int64_t{1} << 40));
    for (;;) {
        const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
        const int ready = device_->waitReadable(int(std::max<std::int64_t>(left.count(), 0)));
        if (ready < 0) return error("cannot wait for a frame", ready);
        if (ready == 0)
            return Status::error("camera '" + device_->path() + "': no frame within " +
                                 std::to_string(timeout.count()) + " ms");

        v4l2_buffer buffer{};
        buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        buffer.memory = V4L2_MEMORY_MMAP;
        if (int ret = device_->ioctl(VIDIOC_DQBUF, &buffer); ret < 0) {
            if (ret == -EAGAIN) continue;  // woken without a frame
            if (ret == -ENODEV) return error("camera vanished during capture", ret);
            return error("cannot dequeue a frame (VIDIOC_DQBUF)", ret);
        }
        if (buffer.index >= buffers_.size())
            return Status::error("camera '" + device_->path() + "' returned unknown buffer " +
                                 std::to_string(buffer.index));
        // A corrupted or short frame (USB packet loss) is dropped, not decoded.
        const bool complete = !(buffer.flags & V4L2_BUF_FLAG_ERROR) && buffer.bytesused >= imageBytes_;
        if (complete) {
            const FrameView source{static_cast<const std::uint8_t*>(buffers_[buffer.index].address), width_, height_,
                                   std::ptrdiff_t(bytesPerLine_),
                                   pixelFormat_ == V4L2_PIX_FMT_YUYV ? PixelFormat::Yuyv : PixelFormat::Bgr8};
            const MutableFrameView target{bgr_.data(), width_, height_, std::ptrdiff_t(width_) * 3, PixelFormat::Bgr8};
            if (pixelFormat_ == V4L2_PIX_FMT_YUYV)
                convertYuyvToBgr(source, target);
            else if (pixelFormat_ == V4L2_PIX_FMT_RGB24)
                convertRgbToBgr(source, target);
            else
                copyBgr(source, target);
        }
        if (int ret = device_->ioctl(VIDIOC_QBUF, &buffer); ret < 0)
            return error("cannot requeue buffer " + std::to_string(buffer.index) + " (VIDIOC_QBUF)", ret);
        if (!complete) continue;

        CapturedFrame frame;
        frame.view = FrameView{bgr_.data(), width_, height_, std::ptrdiff_t(width_) * 3, PixelFormat::Bgr8};
        frame.sequence = buffer.sequence;
        frame.timestampNs = exposureStartNs(buffer);
        frame.exposureUs = exposureUs_;
        frame.analogueGain = analogueGain_;
        return frame;
    }
}

}  // namespace stria::hal
