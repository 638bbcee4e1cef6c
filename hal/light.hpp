#pragma once
// The projector LED (and optionally a status LED or buzzer with the same
// interface).

#include "pipeline/status.hpp"

namespace stria::hal {

class Light {
public:
    virtual ~Light() = default;
    // Must be safe to call from a signal-safe shutdown path: keep it a single
    // write (no allocation, no locks).
    virtual Status set(bool on) = 0;
    virtual bool isOn() const = 0;
};

}  // namespace stria::hal
