#pragma once
// An emulated UVC camera behind the V4l2Device seam: the ioctls a streaming
// client makes (formats, controls, mmap buffers, queue/dequeue), with frames
// the test pushes, a dequeue that finds nothing (timeout) and unplugging
// (ENODEV). It follows the kernel's rules that V4l2Camera relies on: S_FMT
// adjusts the size to one the camera has, buffers cycle through QBUF/DQBUF,
// STREAMOFF returns every buffer.

#include "hal/v4l2/v4l2_device.hpp"

#include <linux/videodev2.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <deque>
#include <map>
#include <utility>
#include <vector>

namespace stria::hal::testing {

struct FakeControl {
    std::int32_t minimum, maximum, defaultValue, value;
};

struct FakeFrame {
    std::vector<std::uint8_t> bytes;
    bool corrupted = false;  // V4L2_BUF_FLAG_ERROR (USB packet loss)
    bool stampedAtEnd = false;  // timestamp taken at the end of the frame, not the start of exposure
};

class FakeUvcDevice final : public V4l2Device {
public:
    struct Format {
        std::uint32_t fourcc;
        bool compressed;
    };

    FakeUvcDevice(std::vector<Format> formats, std::vector<std::pair<int, int>> sizes)
        : formats_(std::move(formats)), sizes_(std::move(sizes))
    {
        controls_[V4L2_CID_EXPOSURE_AUTO] = {0, 3, 3, 3};  // aperture priority, as UVC cameras start
        controls_[V4L2_CID_EXPOSURE_ABSOLUTE] = {3, 2047, 156, 156};
        controls_[V4L2_CID_GAIN] = {0, 255, 32, 32};
        controls_[V4L2_CID_AUTO_WHITE_BALANCE] = {0, 1, 1, 1};
    }

    const std::string& path() const override { return path_; }

    std::map<std::uint32_t, FakeControl>& controls() { return controls_; }
    void pushFrame(FakeFrame frame) { frames_.push_back(std::move(frame)); }
    void unplug() { unplugged_ = true; }
    int mappedBuffers() const { return mapped_; }

    int ioctl(unsigned long request, void* arg) override
    {
        if (unplugged_) return -ENODEV;
        switch (request) {
        case VIDIOC_QUERYCAP: {
            auto* caps = static_cast<v4l2_capability*>(arg);
            *caps = {};
            std::strcpy(reinterpret_cast<char*>(caps->driver), "uvcvideo");
            std::strcpy(reinterpret_cast<char*>(caps->card), "Fake Endoscope");
            caps->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
            caps->capabilities = caps->device_caps | V4L2_CAP_DEVICE_CAPS;
            return 0;
        }
        case VIDIOC_ENUM_FMT: {
            auto* desc = static_cast<v4l2_fmtdesc*>(arg);
            if (desc->index >= formats_.size()) return -EINVAL;
            desc->pixelformat = formats_[desc->index].fourcc;
            desc->flags = formats_[desc->index].compressed ? V4L2_FMT_FLAG_COMPRESSED : 0;
            return 0;
        }
        case VIDIOC_S_FMT: return setFormat(static_cast<v4l2_format*>(arg)->fmt.pix);
        case VIDIOC_G_PARM: static_cast<v4l2_streamparm*>(arg)->parm.capture.timeperframe = {1, 30}; return 0;
        case VIDIOC_QUERYCTRL: {
            auto* query = static_cast<v4l2_queryctrl*>(arg);
            auto it = controls_.find(query->id);
            if (it == controls_.end()) return -EINVAL;
            query->minimum = it->second.minimum;
            query->maximum = it->second.maximum;
            query->default_value = it->second.defaultValue;
            return 0;
        }
        case VIDIOC_S_CTRL:
        case VIDIOC_G_CTRL: {
            auto* control = static_cast<v4l2_control*>(arg);
            auto it = controls_.find(control->id);
            if (it == controls_.end()) return -EINVAL;
            if (request == VIDIOC_S_CTRL) it->second.value = control->value;
            control->value = it->second.value;
            return 0;
        }
        case VIDIOC_REQBUFS: {
            auto* request = static_cast<v4l2_requestbuffers*>(arg);
            if (streaming_ || (mapped_ > 0 && request->count > 0)) return -EBUSY;
            buffers_.assign(request->count, {});
            for (Buffer& buffer : buffers_) buffer.memory.assign(format_.sizeimage, 0);
            return 0;
        }
        case VIDIOC_QUERYBUF: {
            auto* buffer = static_cast<v4l2_buffer*>(arg);
            if (buffer->index >= buffers_.size()) return -EINVAL;
            buffer->length = std::uint32_t(buffers_[buffer->index].memory.size());
            buffer->m.offset = buffer->index * kOffsetStep;
            return 0;
        }
        case VIDIOC_QBUF: {
            auto* buffer = static_cast<v4l2_buffer*>(arg);
            if (buffer->index >= buffers_.size() || buffers_[buffer->index].queued) return -EINVAL;
            buffers_[buffer->index].queued = true;
            queue_.push_back(buffer->index);
            return 0;
        }
        case VIDIOC_DQBUF: return dequeue(static_cast<v4l2_buffer*>(arg));
        case VIDIOC_STREAMON: streaming_ = true; return 0;
        case VIDIOC_STREAMOFF:
            streaming_ = false;
            for (Buffer& buffer : buffers_) buffer.queued = false;
            queue_.clear();
            return 0;
        default: return -ENOTTY;
        }
    }

    int map(std::size_t length, off_t offset, void** address) override
    {
        const std::size_t index = std::size_t(offset) / kOffsetStep;
        if (index >= buffers_.size() || length != buffers_[index].memory.size()) return -EINVAL;
        *address = buffers_[index].memory.data();
        ++mapped_;
        return 0;
    }

    void unmap(void*, std::size_t) override { --mapped_; }

    int waitReadable(int) override
    {
        if (unplugged_) return 1;  // POLLERR: the next DQBUF tells why
        return streaming_ && !frames_.empty() && !queue_.empty() ? 1 : 0;
    }

private:
    struct Buffer {
        std::vector<std::uint8_t> memory;
        bool queued = false;
    };
    static constexpr std::size_t kOffsetStep = 1 << 24;

    int setFormat(v4l2_pix_format& pix)
    {
        if (streaming_) return -EBUSY;
        bool known = false;
        for (const Format& f : formats_) known = known || f.fourcc == pix.pixelformat;
        if (!known) pix.pixelformat = formats_.front().fourcc;
        std::pair<int, int> size = sizes_.front();  // like uvcvideo: the closest it has, here simply the first
        for (auto s : sizes_)
            if (s.first == int(pix.width) && s.second == int(pix.height)) size = s;
        pix.width = std::uint32_t(size.first);
        pix.height = std::uint32_t(size.second);
        pix.bytesperline = pix.width * (pix.pixelformat == V4L2_PIX_FMT_YUYV ? 2 : 3);
        pix.sizeimage = pix.bytesperline * pix.height;
        format_ = pix;
        return 0;
    }

    int dequeue(v4l2_buffer* out)
    {
        if (!streaming_ || frames_.empty() || queue_.empty()) return -EAGAIN;
        const std::uint32_t index = queue_.front();
        queue_.pop_front();
        Buffer& buffer = buffers_[index];
        buffer.queued = false;
        FakeFrame frame = std::move(frames_.front());
        frames_.pop_front();
        std::memcpy(buffer.memory.data(), frame.bytes.data(), std::min(frame.bytes.size(), buffer.memory.size()));
        out->index = index;
        out->bytesused = std::uint32_t(frame.bytes.size());
        out->flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | (frame.corrupted ? V4L2_BUF_FLAG_ERROR : 0) |
                     (frame.stampedAtEnd ? V4L2_BUF_FLAG_TSTAMP_SRC_EOF : V4L2_BUF_FLAG_TSTAMP_SRC_SOE);
        out->sequence = sequence_++;
        out->timestamp = {100, std::int64_t(out->sequence) * 33333};  // 30 fps from t = 100 s
        return 0;
    }

    std::string path_ = "/dev/video0";
    std::vector<Format> formats_;
    std::vector<std::pair<int, int>> sizes_;
    std::map<std::uint32_t, FakeControl> controls_;
    std::vector<Buffer> buffers_;
    std::deque<std::uint32_t> queue_;
    std::deque<FakeFrame> frames_;
    v4l2_pix_format format_{};
    std::uint32_t sequence_ = 0;
    int mapped_ = 0;
    bool streaming_ = false, unplugged_ = false;
};

}  // namespace stria::hal::testing
