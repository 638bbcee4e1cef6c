#pragma once
// One requested GPIO line: the only part of the GPIO backend that depends on
// the libgpiod version. gpiod_line_v1.cpp implements it with libgpiod 1.6
// (Debian 12, Raspberry Pi OS 12); a libgpiod 2.x variant is one sibling file
// implementing the same factory with line requests. GpiodLight and
// GpiodButton build on this interface only, so tests can drive them with an
// emulated line.

#include "pipeline/status.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace stria::hal {

struct LineEdge {
    std::int64_t timeNs;  // CLOCK_MONOTONIC (the kernel's event timestamp)
    bool active;          // the line became active (logical level, active-low applied)
};

class GpiodLine {
public:
    enum class Mode { Output, BothEdges };

    // Requests `offset` on `chip` (name, path, number or label) with consumer
    // label "stria"; outputs start inactive. Errors name the chip, the line,
    // the errno text and, when busy, the current user.
    static Result<std::unique_ptr<GpiodLine>> request(const std::string& chip, int offset, bool activeLow, Mode mode);

    virtual ~GpiodLine() = default;
    virtual const std::string& name() const = 0;  // "line 17 of 'gpiochip0'"
    virtual int setValue(bool active) = 0;         // one ioctl; 0 or -errno
    virtual int value() = 0;                       // 0/1, or -errno
    virtual int eventFd() const = 0;               // readable when edges are pending
    // Reads the pending edges (at most `capacity`): count, or -errno.
    virtual int readEdges(LineEdge* edges, int capacity) = 0;
};

// "GPIO <name>: <what>: <strerror> (<hint>)".
std::string gpioErrorMessage(const std::string& name, const std::string& what, int error);

}  // namespace stria::hal
