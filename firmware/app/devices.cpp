#include "firmware/app/devices.hpp"

#include "hal/sim/sim_button.hpp"
#include "hal/sim/sim_camera.hpp"
#include "hal/sim/sim_light.hpp"

#ifdef STRIA_HAVE_V4L2
#include "hal/v4l2/v4l2_camera.hpp"
#endif
#ifdef STRIA_HAVE_GPIOD
#include "hal/gpiod/gpiod_button.hpp"
#include "hal/gpiod/gpiod_light.hpp"
#endif
#ifdef STRIA_HAVE_LIBCAMERA
#include "hal/libcamera/libcamera_camera.hpp"
#endif

namespace stria::firmware {
namespace {

Result<std::unique_ptr<hal::sim::SimWorld>> makeWorld(const BoardSim& sim)
{
    using namespace hal::sim;
    SimRig rig = sim.rig == "desktop-large" ? desktopRigLarge()
                 : sim.rig == "fingerprint" ? fingerprintRig()
                 : sim.rig == "endoscope"   ? endoscopeRig()
                                            : desktopRig();
    const auto kind = sceneFromName(sim.scene);
    const auto albedo = albedoFromName(sim.albedo);
    if (!kind || !albedo) return Status::error("sim: unknown scene '" + sim.scene + "' or albedo '" + sim.albedo + "'");
    Scene scene = makeScene(*kind, rig, *albedo, sim.seed);
    RenderSettings render;
    render.noiseSigma = sim.noise;
    render.ambient = sim.ambient;
    render.contrast = sim.contrast;
    render.samplesPerPixel = sim.samplesPerPixel;
    render.seed = sim.seed;
    return std::make_unique<SimWorld>(std::move(rig), std::move(scene), render);
}

std::string unavailable(const char* what, const std::string& backend)
{
    return std::string(what) + " backend '" + backend + "' is not built into this stria (see the CMake options STRIA_WITH_*)";
}

Result<std::unique_ptr<hal::Light>> openLight(const char* what, const BoardLight& light, hal::sim::SimWorld* world)
{
    if (light.backend == "sim") {
        if (std::string(what) != "light")
            return Status::error(std::string(what) + ": the simulated head has no such LED (use backend gpiod)");
        return std::unique_ptr<hal::Light>(std::make_unique<hal::sim::SimLight>(*world));
    }
#ifdef STRIA_HAVE_GPIOD
    if (light.backend == "gpiod") {
        auto gpio = hal::GpiodLight::open(light.chip, light.line, light.activeLow);
        if (!gpio) return gpio.status().withContext(std::string(what) + ": ");
        return std::unique_ptr<hal::Light>(std::move(*gpio));
    }
#endif
    return Status::error(unavailable(what, light.backend));
}

}  // namespace

Result<Devices> openDevices(const BoardConfig& board, const std::optional<std::string>& pressScript)
{
    Devices devices;
    const bool usesSim =
        board.camera.backend == "sim" || board.light.backend == "sim" || board.button.backend == "sim";
    if (usesSim) {
        auto world = makeWorld(board.sim);
        if (!world) return world.status();
        devices.world = std::move(*world);
    }

    const BoardCamera& cam = board.camera;
    if (cam.backend == "sim") {
        devices.camera = std::make_unique<hal::sim::SimCamera>(*devices.world, board.sim.frameIntervalUs);
#ifdef STRIA_HAVE_V4L2
    } else if (cam.backend == "v4l2") {
        auto camera = hal::V4l2Camera::open(cam.device);
        if (!camera) return camera.status();
        devices.camera = std::move(*camera);
#endif
#ifdef STRIA_HAVE_LIBCAMERA
    } else if (cam.backend == "libcamera") {
        auto camera = hal::LibcameraCamera::open(cam.device);
        if (!camera) return camera.status();
        devices.camera = std::move(*camera);
#endif
    } else {
        return Status::error(unavailable("camera", cam.backend));
    }

    auto light = openLight("light", board.light, devices.world.get());
    if (!light) return light.status();
    devices.light = std::move(*light);
    if (board.statusLed) {
        auto status = openLight("status_led", *board.statusLed, devices.world.get());
        if (!status) return status.status();
        devices.statusLed = std::move(*status);
    }

    const BoardButton& btn = board.button;
    if (btn.backend == "sim") {
        auto presses = hal::sim::parsePressScript(pressScript.value_or(board.sim.presses));
        if (!presses) return presses.status();
        devices.button = std::make_unique<hal::sim::SimButton>(std::move(*presses), btn.debounceMs, board.sim.realTime);
#ifdef STRIA_HAVE_GPIOD
    } else if (btn.backend == "gpiod") {
        auto gpio = hal::GpiodButton::open(btn.chip, btn.line, btn.activeLow, btn.debounceMs);
        if (!gpio) return gpio.status().withContext("button: ");
        devices.button = std::move(*gpio);
#endif
    } else {
        return Status::error(unavailable("button", btn.backend));
    }
    return devices;
}

}  // namespace stria::firmware
