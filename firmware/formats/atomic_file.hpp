#pragma once
// Writing result files so that a reader never sees a half-written one: write
// to a temporary file in the same directory, fsync it, rename it over the
// final name, fsync the directory. On any failure the temporary is removed
// and the error names the path and the reason (e.g. "No space left on device").

#include "pipeline/status.hpp"

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace stria::firmware {

class AtomicFile {
public:
    // Creates "<path>.tmp-XXXXXX" beside `path`.
    static Result<AtomicFile> create(const std::string& path);
    AtomicFile(AtomicFile&& other) noexcept;
    AtomicFile& operator=(AtomicFile&&) = delete;
    AtomicFile(const AtomicFile&) = delete;
    ~AtomicFile();  // removes the temporary unless commit() succeeded

    Status write(const void* data, std::size_t size);
    // fsync, rename to the final path, fsync the directory.
    Status commit();
    const std::string& path() const { return path_; }
    const std::string& temporaryPath() const { return tmpPath_; }

private:
    AtomicFile(std::string path, std::string tmpPath, int fd);
    std::string path_;
    std::string tmpPath_;
    int fd_ = -1;
    bool committed_ = false;
    Status firstError_;
};

Status writeFileAtomically(const std::string& path, const void* data, std::size_t size);
Status writeFileAtomically(const std::string& path, const std::vector<unsigned char>& bytes);
Status writeFileAtomically(const std::string& path, const std::string& text);

}  // namespace stria::firmware
