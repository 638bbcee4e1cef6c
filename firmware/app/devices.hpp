#pragma once
// The one place where a board file's backend names become HAL objects.
#include "firmware/formats/board_file.hpp"
#include "hal/button.hpp"
#include "hal/camera.hpp"
#include "hal/light.hpp"
#include "hal/sim/sim_world.hpp"

#include <memory>
#include <optional>
#include <string>

namespace stria::firmware {

struct Devices {
    // Declared first so it outlives the simulated devices that refer to it.
    std::unique_ptr<hal::sim::SimWorld> world;  // set when any backend is "sim"
    std::unique_ptr<hal::Camera> camera;
    std::unique_ptr<hal::Light> light;
    std::unique_ptr<hal::Button> button;
    std::unique_ptr<hal::Light> statusLed;  // optional
};

// `pressScript` replaces the board's sim.presses (the simulated button only).
Result<Devices> openDevices(const BoardConfig& board, const std::optional<std::string>& pressScript = std::nullopt);

}  // namespace stria::firmware
