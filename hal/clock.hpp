#pragma once
// CLOCK_MONOTONIC in nanoseconds: the time base of frame timestamps, LED
// change logs and scan records (immune to wall-clock steps by NTP).

#include <cstdint>
#include <ctime>

namespace stria::hal {

inline std::int64_t monotonicNs()
{
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

// Sleeps until the monotonic time tNs (no-op if it has passed).
void sleepUntilNs(std::int64_t tNs);

}  // namespace stria::hal
