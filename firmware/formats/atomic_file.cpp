#include "firmware/formats/atomic_file.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <stdlib.h>
#include <unistd.h>

namespace stria::firmware {
namespace {

std::string errnoText() { return std::strerror(errno); }

std::string directoryOf(const std::string& path)
{
    const auto slash = path.find_last_of('/');
    if (slash == std::string::npos) return ".";
    if (slash == 0) return "/";
    return path.substr(0, slash);
}

}  // namespace

AtomicFile::AtomicFile(std::string path, std::string tmpPath, int fd)
    : path_(std::move(path)), tmpPath_(std::move(tmpPath)), fd_(fd)
{
}

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : path_(std::move(other.path_)), tmpPath_(std::move(other.tmpPath_)), fd_(other.fd_),
      committed_(other.committed_), firstError_(other.firstError_)
{
    other.fd_ = -1;
    other.committed_ = true;  // the moved-from object owns nothing
}

AtomicFile::~AtomicFile()
{
    if (fd_ >= 0) ::close(fd_);
    if (!committed_ && !tmpPath_.empty()) ::unlink(tmpPath_.c_str());
}

Result<AtomicFile> AtomicFile::create(const std::string& path)
{
    std::string tmp = path + ".tmp-XXXXXX";
    const int fd = ::mkstemp(tmp.data());
    if (fd < 0) return Status::error("cannot create '" + path + "': " + errnoText());
    ::fchmod(fd, 0644);
    return AtomicFile(path, tmp, fd);
}

Status AtomicFile::write(const void* data, std::size_t size)
{
    if (!firstError_.isOk()) return firstError_;
    const auto* p = static_cast<const unsigned char*>(data);
    while (size > 0) {
        const ssize_t n = ::write(fd_, p, size);
        if (n < 0) {
            if (errno == EINTR) continue;
            firstError_ = Status::error("cannot write '" + path_ + "': " + errnoText());
            return firstError_;
        }
        p += n;
        size -= static_cast<std::size_t>(n);
    }
    return Status::ok();
}

Status AtomicFile::commit()
{
    if (!firstError_.isOk()) return firstError_;
    if (::fsync(fd_) != 0) return Status::error("cannot write '" + path_ + "' to disk: " + errnoText());
    if (::close(fd_) != 0) {
        fd_ = -1;
        return Status::error("cannot write '" + path_ + "': " + errnoText());
    }
    fd_ = -1;
    if (::rename(tmpPath_.c_str(), path_.c_str()) != 0)
        return Status::error("cannot rename '" + tmpPath_ + "' to '" + path_ + "': " + errnoText());
    committed_ = true;
    const int dir = ::open(directoryOf(path_).c_str(), O_RDONLY | O_DIRECTORY);
    if (dir >= 0) {
        ::fsync(dir);
        ::close(dir);
    }
    return Status::ok();
}

Status writeFileAtomically(const std::string& path, const void* data, std::size_t size)
{
    auto file = AtomicFile::create(path);
    if (!file) return file.status();
    if (Status s = file->write(data, size); !s) return s;
    return file->commit();
}

Status writeFileAtomically(const std::string& path, const std::vector<unsigned char>& bytes)
{
    return writeFileAtomically(path, bytes.data(), bytes.size());
}

Status writeFileAtomically(const std::string& path, const std::string& text)
{
    return writeFileAtomically(path, text.data(), text.size());
}

}  // namespace stria::firmware
