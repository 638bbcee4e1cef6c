#include "hal/v4l2/v4l2_device.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace stria::hal {
namespace {

class SyscallV4l2Device final : public V4l2Device {
public:
    SyscallV4l2Device(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}
    ~SyscallV4l2Device() override { ::close(fd_); }

    const std::string& path() const override { return path_; }

    int ioctl(unsigned long request, void* arg) override
    {
        int ret;
        do {
            ret = ::ioctl(fd_, request, arg);
        } while (ret < 0 && errno == EINTR);
        return ret < 0 ? -errno : 0;
    }

    int map(std::size_t length, off_t offset, void** address) override
    {
        void* mapped = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, offset);
        if (mapped == MAP_FAILED) return -errno;
        *address = mapped;
        return 0;
    }

    void unmap(void* address, std::size_t length) override { ::munmap(address, length); }

    int waitReadable(int timeoutMs) override
    {
        pollfd pfd{fd_, POLLIN, 0};
        const int ret = ::poll(&pfd, 1, timeoutMs);
        if (ret < 0) return errno == EINTR ? 0 : -errno;
        return ret > 0 ? 1 : 0;
    }

private:
    std::string path_;
    int fd_;
};

const char* hint(int error)
{
    switch (error) {
    case ENOENT: return "is the camera plugged in?";
    case EBUSY: return "another program is using the camera";
    case EACCES:
    case EPERM: return "add the user to group 'video'";
    case ENODEV:
    case ENXIO: return "the camera was unplugged or its driver went away";
    default: return nullptr;
    }
}

}  // namespace

std::string v4l2ErrorMessage(const std::string& path, const std::string& what, int error)
{
    std::string message = "camera '" + path + "': " + what + ": " + std::strerror(error);
    if (const char* h = hint(error)) message += std::string(" (") + h + ")";
    return message;
}

Result<std::unique_ptr<V4l2Device>> openV4l2Device(const std::string& path)
{
    const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return Status::error(v4l2ErrorMessage(path, "cannot open", errno));
    return std::unique_ptr<V4l2Device>(std::make_unique<SyscallV4l2Device>(path, fd));
}

}  // namespace stria::hal
