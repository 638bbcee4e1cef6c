#include "hal/gpiod/gpiod_button.hpp"

#include "hal/clock.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>

namespace stria::hal {

GpiodButton::GpiodButton(std::unique_ptr<GpiodLine> line, int debounceMs, int interruptFd)
    : line_(std::move(line)), debouncer_(std::int64_t(debounceMs) * 1'000'000), interruptFd_(interruptFd)
{
}

GpiodButton::~GpiodButton() { ::close(interruptFd_); }

Result<std::unique_ptr<GpiodButton>> GpiodButton::open(const std::string& chip, int line, bool activeLow,
                                                       int debounceMs)
{
    auto requested = GpiodLine::request(chip, line, activeLow, GpiodLine::Mode::BothEdges);
    if (!requested) return requested.status();
    return open(std::move(*requested), debounceMs);
}

Result<std::unique_ptr<GpiodButton>> GpiodButton::open(std::unique_ptr<GpiodLine> line, int debounceMs)
{
    const int fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (fd < 0) return Status::error(gpioErrorMessage(line->name(), "cannot create an eventfd", errno));
    // A button held at start-up is not a press: the Debouncer starts
    // released and only counts a release->press change it sees.
    return std::unique_ptr<GpiodButton>(new GpiodButton(std::move(line), debounceMs, fd));
}

void GpiodButton::interrupt()
{
    const std::uint64_t one = 1;
    [[maybe_unused]] ssize_t written = ::write(interruptFd_, &one, sizeof one);
}

Status GpiodButton::feedPendingEdges()
{
    pollfd fd{line_->eventFd(), POLLIN, 0};
    if (::poll(&fd, 1, 0) <= 0 || !(fd.revents & (POLLIN | POLLERR))) return Status::ok();
    LineEdge edges[16];
    const int count = line_->readEdges(edges, 16);
    if (count < 0) return Status::error(gpioErrorMessage(line_->name(), "cannot read button edges", -count));
    for (int i = 0; i < count; ++i) {
        // An edge can reach us after the Debouncer was advanced past its
        // timestamp (it happened between the last read and the clock read).
        lastTimeNs_ = std::max(edges[i].timeNs, lastTimeNs_);
        debouncer_.edge(lastTimeNs_, edges[i].active);
    }
    return Status::ok();
}

Result<ButtonWait> GpiodButton::waitForPress(std::chrono::milliseconds timeout)
{
    const std::int64_t timeoutMs = std::min<std::int64_t>(timeout.count(), std::int64_t{1} << 40);  // no overflow
    const std::int64_t endNs = monotonicNs() + timeoutMs * 1'000'000;
    for (;;) {
        // Edges first, so the Debouncer sees them before it is advanced to now.
        if (Status s = feedPendingEdges(); !s) return s;
        const std::int64_t nowNs = lastTimeNs_ = std::max(monotonicNs(), lastTimeNs_);
        if (debouncer_.pressBy(nowNs)) return ButtonWait::Pressed;
        if (nowNs >= endNs) return ButtonWait::TimedOut;
        const std::int64_t wakeNs = std::min(endNs, debouncer_.deadline().value_or(endNs));
        const int waitMs = int((wakeNs - nowNs + 999'999) / 1'000'000);

        pollfd fds[2] = {{interruptFd_, POLLIN, 0}, {line_->eventFd(), POLLIN, 0}};
        if (::poll(fds, 2, waitMs) < 0 && errno != EINTR)
            return Status::error(gpioErrorMessage(line_->name(), "cannot wait for the button", errno));
        if (fds[0].revents & POLLIN) {
            std::uint64_t count;
            [[maybe_unused]] ssize_t read = ::read(interruptFd_, &count, sizeof count);
            return ButtonWait::Interrupted;
        }
    }
}

}  // namespace stria::hal
