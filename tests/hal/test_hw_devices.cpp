// openDevices() with the real heads' board files on a machine without their
// hardware: start-up fails with a message naming the missing device, the way
// `stria scan` reports it (the error of each backend's open()).
#include "firmware/app/devices.hpp"

#include <gtest/gtest.h>

namespace stria::firmware {
namespace {

BoardConfig loadBoard(const char* folder)
{
    auto board = loadBoardFile(std::string(STRIA_SOURCE_DIR) + "/board/" + folder + "/board.yaml");
    EXPECT_TRUE(board.isOk()) << board.message();
    return board ? *board : BoardConfig{};
}

#ifdef STRIA_HAVE_V4L2
TEST(HwDevices, EndoscopeWithoutItsCameraNamesTheDeviceNode)
{
    auto devices = openDevices(loadBoard("endoscope-pi5"));
    ASSERT_FALSE(devices.isOk());
    EXPECT_EQ(devices.message(),
              "camera '/dev/stria-endoscope': cannot open: No such file or directory (is the camera plugged in?)");
}
#endif

#ifdef STRIA_HAVE_LIBCAMERA
TEST(HwDevices, FingerprintHeadWithoutCameraSaysNoneWasFound)
{
    auto devices = openDevices(loadBoard("fingerprint-cm4"));
    ASSERT_FALSE(devices.isOk());
    EXPECT_EQ(devices.message(), "no libcamera camera found (check the sensor's dtoverlay in config.txt; `cam --list` "
                                 "shows what libcamera sees)");
}
#endif

#ifdef STRIA_HAVE_GPIOD
TEST(HwDevices, MissingGpioChipIsNamedWithTheBoardKey)
{
    // The endoscope head with a simulated camera: the LED's chip is next.
    BoardConfig board = loadBoard("endoscope-pi5");
    board.camera.backend = "sim";
    board.sim.rig = "endoscope";
    board.sim.scene = "tube";
    auto devices = openDevices(board);
    ASSERT_FALSE(devices.isOk());
    EXPECT_EQ(devices.message(),
              "light: GPIO chip 'pinctrl-rp1': cannot open: No such file or directory (`gpiodetect` lists the chips)");
}
#endif

}  // namespace
}  // namespace stria::firmware
