#include "hal/sim/sim_world.hpp"

#include "hal/clock.hpp"

#include <algorithm>

namespace stria::hal::sim {

void SimWorld::setLed(bool on)
{
    // Log first, then publish the state: a reader that sees the new state
    // finds its change in the log.
    const std::uint64_t index = logCount_.fetch_add(1);
    log_[index % kLogCapacity].store(monotonicNs() * 2 + (on ? 1 : 0));
    led_.store(on);
}

std::vector<LedEvent> SimWorld::ledLog() const
{
    const std::uint64_t count = logCount_.load();
    const std::uint64_t first = count > kLogCapacity ? count - kLogCapacity : 0;
    std::vector<LedEvent> events;
    events.reserve(count - first);
    for (std::uint64_t i = first; i < count; ++i) {
        const std::int64_t packed = log_[i % kLogCapacity].load();
        events.push_back({packed >> 1, (packed & 1) != 0});
    }
    // Concurrent writers may publish slightly out of order.
    std::stable_sort(events.begin(), events.end(), [](const LedEvent& a, const LedEvent& b) { return a.timeNs < b.timeNs; });
    return events;
}

bool SimWorld::ledOnThroughout(std::int64_t beginNs, std::int64_t endNs) const
{
    // Walk back from the newest change: the LED must have been switched on
    // at or before beginNs with no change in between.
    const std::uint64_t count = logCount_.load();
    const std::uint64_t first = count > kLogCapacity ? count - kLogCapacity : 0;
    for (std::uint64_t i = count; i > first; --i) {
        const std::int64_t packed = log_[(i - 1) % kLogCapacity].load();
        const std::int64_t t = packed >> 1;
        const bool on = (packed & 1) != 0;
        if (t > endNs) continue;
        if (t > beginNs) return false;  // a change inside the exposure
        return on;
    }
    return false;  // never switched on (or the change fell out of the log)
}

bool SimWorld::takeCaptureTimeout()
{
    int pending = captureTimeouts_.load();
    while (pending > 0) {
        if (captureTimeouts_.compare_exchange_weak(pending, pending - 1)) return true;
    }
    return false;
}

}  // namespace stria::hal::sim
