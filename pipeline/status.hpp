#pragma once
// Error reporting without exceptions across library boundaries: a Status is
// "ok" or carries a human-readable message naming the problem (the file, the
// key, the value). Result<T> holds either a T or such a message.

#include <cassert>
#include <optional>
#include <string>
#include <utility>

namespace stria {

class Status {
public:
    Status() = default;
    static Status ok() { return Status(); }
    static Status error(std::string message) { return Status(std::move(message), true); }

    bool isOk() const { return !failed_; }
    explicit operator bool() const { return isOk(); }
    const std::string& message() const { return message_; }

    // Prefixes context ("calibration 'x.yaml': ") to an error message.
    Status withContext(const std::string& context) const
    {
        return failed_ ? Status(context + message_, true) : *this;
    }

private:
    Status(std::string message, bool failed) : message_(std::move(message)), failed_(failed) {}
    std::string message_;
    bool failed_ = false;
};

template <typename T>
class Result {
public:
    Result(T value) : value_(std::move(value)) {}  // NOLINT: implicit by design
    Result(Status status) : status_(std::move(status)) { assert(!status_.isOk()); }  // NOLINT

    bool isOk() const { return value_.has_value(); }
    explicit operator bool() const { return isOk(); }
    const Status& status() const { return status_; }
    const std::string& message() const { return status_.message(); }

    T& value() & { assert(value_); return *value_; }
    const T& value() const& { assert(value_); return *value_; }
    T&& value() && { assert(value_); return std::move(*value_); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }
    T& operator*() & { return value(); }
    const T& operator*() const& { return value(); }

private:
    std::optional<T> value_;
    Status status_;
};

}  // namespace stria
