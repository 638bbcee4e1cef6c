#pragma once
// A maximum on-time guard for the projector LED: a thread that forces the LED
// off if it stays on longer than the board allows (a hung camera, a stuck
// loop). The LED is also switched off on every normal and error path; this is
// the backstop for the paths nobody thought of.
#include "hal/light.hpp"

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace stria::firmware {

class LedWatchdog {
public:
    LedWatchdog(hal::Light& light, std::chrono::milliseconds maxOn);
    ~LedWatchdog();
    LedWatchdog(const LedWatchdog&) = delete;
    LedWatchdog& operator=(const LedWatchdog&) = delete;

    void arm();     // the LED was just switched on
    void disarm();  // the LED was just switched off
    // The watchdog switched the LED off since the last arm().
    bool fired() const;

private:
    void watch();

    hal::Light& light_;
    const std::chrono::milliseconds maxOn_;
    mutable std::mutex mutex_;
    std::condition_variable wake_;
    std::chrono::steady_clock::time_point deadline_;
    bool armed_ = false;
    bool fired_ = false;
    bool quit_ = false;
    std::thread thread_;  // last: starts after the state above exists
};

}  // namespace stria::firmware
