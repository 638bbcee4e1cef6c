#include "firmware/app/led_watchdog.hpp"

#include "firmware/app/log.hpp"

namespace stria::firmware {

LedWatchdog::LedWatchdog(hal::Light& light, std::chrono::milliseconds maxOn) :
    light_(light), maxOn_(maxOn), thread_([this] { watch(); })
{
}

LedWatchdog::~LedWatchdog()
{
    {
        std::lock_guard lock(mutex_);
        quit_ = true;
    }
    wake_.notify_one();
    thread_.join();
}

void LedWatchdog::arm()
{
    {
        std::lock_guard lock(mutex_);
        deadline_ = std::chrono::steady_clock::now() + maxOn_;
        armed_ = true;
        fired_ = false;
    }
    wake_.notify_one();
}

void LedWatchdog::disarm()
{
    std::lock_guard lock(mutex_);
    armed_ = false;
}

bool LedWatchdog::fired() const
{
    std::lock_guard lock(mutex_);
    return fired_;
}

void LedWatchdog::watch()
{
    std::unique_lock lock(mutex_);
    while (!quit_) {
        if (!armed_) {
            wake_.wait(lock);
            continue;
        }
        if (wake_.wait_until(lock, deadline_) == std::cv_status::timeout && armed_ &&
            std::chrono::steady_clock::now() >= deadline_) {
            const Status s = light_.set(false);
            armed_ = false;
            fired_ = true;
            logError("LED forced off by the watchdog after %lld ms%s%s", static_cast<long long>(maxOn_.count()),
                     s ? "" : ": ", s.message().c_str());
        }
    }
}

}  // namespace stria::firmware
