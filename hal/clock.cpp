#include "hal/clock.hpp"

#include <cerrno>

namespace stria::hal {

void sleepUntilNs(std::int64_t tNs)
{
    const timespec until{static_cast<time_t>(tNs / 1000000000), static_cast<long>(tNs % 1000000000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr) == EINTR) {
    }
}

}  // namespace stria::hal
