// 1000 simulated scans in one process: every scan succeeds and the process
// does not grow (resident set and heap in use measured after a warm-up and
// at the end). A 260x200 crop of the desktop camera keeps it quick; outputs
// are not written (--no-save), so the test measures the loop and the decoder.
// 1 ms exposure at gain 10 is as bright as the nominal 10 ms at gain 1.
// The LED watchdog is 1 s: a scan keeps the LED on for a few ms, but on a
// loaded machine the scheduler once stalled a scan past a 100 ms watchdog.
#include "firmware/app/scanner.hpp"
#include "firmware/formats/atomic_file.hpp"
#include "firmware/formats/calibration_file.hpp"
#include "firmware/formats/pattern_file.hpp"
#include "hal/clock.hpp"
#include "hal/sim/sim_button.hpp"
#include "hal/sim/sim_camera.hpp"
#include "hal/sim/sim_light.hpp"

#include <gtest/gtest.h>

#include <malloc.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

using namespace stria;
using namespace stria::firmware;

namespace {

// The centre of the desktop camera, same optics: a smaller sensor.
hal::sim::SimRig croppedDesktopRig(int width, int height)
{
    hal::sim::SimRig full = hal::sim::desktopRig();
    pipeline::LensModel camera = full.rig.camera();
    camera.K(0, 2) -= (camera.width - width) / 2;
    camera.K(1, 2) -= (camera.height - height) / 2;
    camera.width = width;
    camera.height = height;
    auto rig = pipeline::RigModel::create(camera, full.rig.projector(), full.rig.R(), full.rig.T());
    EXPECT_TRUE(rig.isOk()) << rig.message();
    return {*rig, full.pattern, full.workingDistanceMm};
}

long residentBytes()
{
    long pages = 0, resident = 0;
    FILE* f = std::fopen("/proc/self/statm", "r");
    if (!f) return -1;
    const int n = std::fscanf(f, "%ld %ld", &pages, &resident);
    std::fclose(f);
    return n == 2 ? resident * sysconf(_SC_PAGESIZE) : -1;
}

}  // namespace

TEST(ScanSoak, ThousandScansInConstantMemory)
{
    std::string tmpl = (std::filesystem::temp_directory_path() / "stria-soak-XXXXXX").string();
    const std::string dir = mkdtemp(tmpl.data());
    hal::sim::SimRig rig = croppedDesktopRig(260, 200);
    ASSERT_TRUE(saveCalibrationFile(rig.rig, dir + "/calibration.yaml"));
    ASSERT_TRUE(savePatternFile(rig.pattern, dir + "/pattern.yaml"));
    auto board = parseBoard(R"(name: soak
camera: {backend: sim, width: 260, height: 200, exposure_us: 1000, gain: 10, timeout_ms: 200}
light: {backend: sim, max_on_ms: 1000}
button: {backend: sim}
pattern: pattern.yaml
calibration: calibration.yaml
settle_ms: 1
)",
                            dir + "/board.yaml");
    ASSERT_TRUE(board.isOk()) << board.message();

    Devices devices;
    hal::sim::RenderSettings render;
    render.samplesPerPixel = 1;
    render.noiseSigma = 2;
    hal::sim::Scene scene = hal::sim::makeScene(hal::sim::SceneKind::TexturedRelief, rig, hal::sim::Albedo::Coloured, 3);
    devices.world = std::make_unique<hal::sim::SimWorld>(std::move(rig), std::move(scene), render);
    devices.camera = std::make_unique<hal::sim::SimCamera>(*devices.world, 1000);
    devices.light = std::make_unique<hal::sim::SimLight>(*devices.world);
    devices.button = std::make_unique<hal::sim::SimButton>(std::vector<hal::sim::ScriptedPress>{}, 20, false);
    const hal::sim::SimWorld& world = *devices.world;
    ScanOptions options;
    options.writeOutputs = false;
    auto scanner = Scanner::create(*board, std::move(devices), options);
    ASSERT_TRUE(scanner.isOk()) << scanner.message();

    constexpr int kWarmUp = 20, kScans = 1000;
    int failed = 0, minPoints = 1 << 30;
    long rssAfterWarmUp = 0;
    std::size_t heapAfterWarmUp = 0;
    for (int i = 0; i < kScans; ++i) {
        const ScanResult result = (*scanner)->scanOnce(hal::monotonicNs());
        failed += !result.record.ok;
        minPoints = std::min(minPoints, result.record.points);
        if (i + 1 == kWarmUp) {
            rssAfterWarmUp = residentBytes();
            heapAfterWarmUp = mallinfo2().uordblks;
        }
    }
    const long rssGrowth = residentBytes() - rssAfterWarmUp;
    const long heapGrowth = static_cast<long>(mallinfo2().uordblks) - static_cast<long>(heapAfterWarmUp);
    std::printf("%d scans, %d failed, >= %d points each; after the warm-up: RSS %+ld bytes, heap in use %+ld bytes\n",
                kScans, failed, minPoints, rssGrowth, heapGrowth);
    EXPECT_EQ(failed, 0);
    // Every scan really decodes (about 950-1100 points on this crop, depending
    // on the decoder's version), so the memory figures are for full scans.
    EXPECT_GT(minPoints, 500);
    EXPECT_FALSE(world.ledOn());
    EXPECT_LT(rssGrowth, 256 * 1024);
    EXPECT_LT(heapGrowth, 16 * 1024);
    scanner->reset();
    std::filesystem::remove_all(dir);
}
