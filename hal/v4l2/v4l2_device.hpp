#pragma once
// The seam between V4l2Camera and the kernel: the four system calls a V4L2
// streaming client makes on its device node. The real implementation calls
// them on an open file descriptor; tests put an emulated UVC camera behind the
// same interface, because umockdev can emulate ioctls but not mmap().

#include "pipeline/status.hpp"

#include <sys/types.h>

#include <cstddef>
#include <memory>
#include <string>

namespace stria::hal {

class V4l2Device {
public:
    virtual ~V4l2Device() = default;
    virtual const std::string& path() const = 0;
    // 0 on success, -errno on failure (EINTR is retried).
    virtual int ioctl(unsigned long request, void* arg) = 0;
    // Maps a buffer (offset from VIDIOC_QUERYBUF); 0 or -errno.
    virtual int map(std::size_t length, off_t offset, void** address) = 0;
    virtual void unmap(void* address, std::size_t length) = 0;
    // Waits until a buffer can be dequeued (or the device reports an error):
    // 1 ready, 0 timed out, -errno.
    virtual int waitReadable(int timeoutMs) = 0;
};

// Opens a device node non-blocking. Errors name the path, the errno text and
// the likely cause (unplugged, busy, permissions).
Result<std::unique_ptr<V4l2Device>> openV4l2Device(const std::string& path);

// "camera '/dev/video0': <what>: <strerror> (<hint>)".
std::string v4l2ErrorMessage(const std::string& path, const std::string& what, int error);

}  // namespace stria::hal
