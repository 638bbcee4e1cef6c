#pragma once
// The scan button.

#include "pipeline/status.hpp"

#include <chrono>

namespace stria::hal {

enum class ButtonWait { Pressed, TimedOut, Interrupted };

class Button {
public:
    virtual ~Button() = default;
    // Waits for a debounced press (release->press edge, then stable for the debounce time).
    virtual Result<ButtonWait> waitForPress(std::chrono::milliseconds timeout) = 0;
    // Wakes a waiting waitForPress() (shutdown); thread- and signal-safe (eventfd/pipe).
    virtual void interrupt() = 0;
};

}  // namespace stria::hal
