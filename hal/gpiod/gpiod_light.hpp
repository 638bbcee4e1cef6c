#pragma once
// The projector LED (or a status LED) on a GPIO output line.

#include "hal/gpiod/gpiod_line.hpp"
#include "hal/light.hpp"

#include <atomic>
#include <memory>
#include <string>

namespace stria::hal {

class GpiodLight final : public Light {
public:
    // Requests the line once, as output, initially off.
    static Result<std::unique_ptr<GpiodLight>> open(const std::string& chip, int line, bool activeLow);
    explicit GpiodLight(std::unique_ptr<GpiodLine> line) : line_(std::move(line)) {}

    // One gpiod_line_set_value() (a single ioctl): safe in the shutdown path.
    Status set(bool on) override;
    bool isOn() const override { return on_.load(std::memory_order_relaxed); }

private:
    std::unique_ptr<GpiodLine> line_;
    std::atomic<bool> on_{false};
};

}  // namespace stria::hal
