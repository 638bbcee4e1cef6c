#include "hal/sim/sim_button.hpp"

#include "hal/clock.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>

namespace stria::hal::sim {
namespace {

constexpr std::int64_t kMs = 1000000;

// A bouncing contact: three short chatters before the level holds (press and release).
constexpr int kBounceMs[] = {0, 2, 3, 5, 6};

}  // namespace

Result<std::vector<ScriptedPress>> parsePressScript(const std::string& script)
{
    std::vector<ScriptedPress> presses;
    std::size_t pos = 0;
    while (pos <= script.size() && !script.empty()) {
        const std::size_t comma = std::min(script.find(',', pos), script.size());
        std::string item = script.substr(pos, comma - pos);
        item.erase(0, item.find_first_not_of(' '));
        item.erase(item.find_last_not_of(' ') + 1);
        ScriptedPress press;
        if (!item.empty() && item.back() == 'b') {
            press.bounce = true;
            item.pop_back();
        }
        const auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), press.timeMs);
        if (item.empty() || ec != std::errc() || end != item.data() + item.size() || press.timeMs < 0)
            return Status::error("press script '" + script + "': '" + script.substr(pos, comma - pos) +
                                 "' is not a time in ms (optionally followed by b for bounce)");
        if (!presses.empty() && press.timeMs < presses.back().timeMs)
            return Status::error("press script '" + script + "': times must not decrease (" +
                                 std::to_string(press.timeMs) + " after " + std::to_string(presses.back().timeMs) + ")");
        presses.push_back(press);
        pos = comma + 1;
    }
    return presses;
}

SimButton::SimButton(std::vector<ScriptedPress> presses, int debounceMs, bool realTime) :
    debouncer_(std::int64_t{debounceMs} * kMs), realTime_(realTime),
    interruptFd_(eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK))
{
    for (const ScriptedPress& p : presses) {
        const std::int64_t down = std::int64_t{p.timeMs} * kMs;
        const std::int64_t up = down + std::int64_t{kHoldMs} * kMs;
        for (std::int64_t start : {down, up}) {
            const bool active = start == down;
            if (p.bounce) {
                for (std::size_t i = 0; i < std::size(kBounceMs); ++i)
                    edges_.push_back({start + kBounceMs[i] * kMs, (i % 2 == 0) == active});
            } else {
                edges_.push_back({start, active});
            }
        }
    }
    std::stable_sort(edges_.begin(), edges_.end(), [](const Edge& a, const Edge& b) { return a.timeNs < b.timeNs; });
}

SimButton::~SimButton()
{
    if (interruptFd_ >= 0) close(interruptFd_);
}

Result<ButtonWait> SimButton::waitForPress(std::chrono::milliseconds timeout)
{
    // In real time, edges that came while nobody waited (during a scan) are
    // still queued on the line, as with a GPIO event queue.
    if (startNs_ == 0) startNs_ = monotonicNs();
    if (realTime_) nowNs_ = std::max(nowNs_, monotonicNs() - startNs_);
    constexpr std::chrono::milliseconds kLongest = std::chrono::hours(24);
    const std::int64_t timeoutAt = nowNs_ + std::chrono::nanoseconds(std::min(timeout, kLongest)).count();
    for (;;) {
        // Pending interrupt? (consumed, so the next wait works again)
        std::uint64_t value = 0;
        if (read(interruptFd_, &value, sizeof value) == sizeof value) return ButtonWait::Interrupted;

        // The next thing that happens on the line: an edge or a debounce deadline.
        std::int64_t next = INT64_MAX;
        if (nextEdge_ < edges_.size()) next = edges_[nextEdge_].timeNs;
        if (const auto deadline = debouncer_.deadline()) next = std::min(next, *deadline);
        if (next == INT64_MAX) return ButtonWait::Interrupted;  // script used up
        next = std::min(next, timeoutAt);
        if (realTime_) {
            const std::int64_t waitNs = startNs_ + next - monotonicNs();
            if (waitNs > 0) {
                pollfd fd{interruptFd_, POLLIN, 0};
                if (poll(&fd, 1, static_cast<int>((waitNs + kMs - 1) / kMs)) > 0) continue;
            }
        }
        nowNs_ = std::max(nowNs_, next);
        while (nextEdge_ < edges_.size() && edges_[nextEdge_].timeNs <= nowNs_) {
            debouncer_.edge(edges_[nextEdge_].timeNs, edges_[nextEdge_].active);
            ++nextEdge_;
        }
        if (debouncer_.pressBy(nowNs_)) return ButtonWait::Pressed;
        if (nowNs_ >= timeoutAt) return ButtonWait::TimedOut;
    }
}

void SimButton::interrupt()
{
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto written = write(interruptFd_, &one, sizeof one);
}

}  // namespace stria::hal::sim
