#pragma once
// The simulated projector LED: writes its state into the SimWorld.

#include "hal/light.hpp"
#include "hal/sim/sim_world.hpp"

namespace stria::hal::sim {

class SimLight final : public Light {
public:
    explicit SimLight(SimWorld& world) : world_(world) {}
    Status set(bool on) override
    {
        world_.setLed(on);
        return Status::ok();
    }
    bool isOn() const override { return world_.ledOn(); }

private:
    SimWorld& world_;
};

}  // namespace stria::hal::sim
