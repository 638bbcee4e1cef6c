#include "hal/gpiod/gpiod_light.hpp"

namespace stria::hal {

Result<std::unique_ptr<GpiodLight>> GpiodLight::open(const std::string& chip, int line, bool activeLow)
{
    auto requested = GpiodLine::request(chip, line, activeLow, GpiodLine::Mode::Output);
    if (!requested) return requested.status();
    return std::make_unique<GpiodLight>(std::move(*requested));
}

Status GpiodLight::set(bool on)
{
    if (int ret = line_->setValue(on); ret < 0)
        return Status::error(gpioErrorMessage(line_->name(), on ? "cannot switch on" : "cannot switch off", -ret));
    on_.store(on, std::memory_order_relaxed);
    return Status::ok();
}

}  // namespace stria::hal
