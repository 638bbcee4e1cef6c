// V4l2Camera against an emulated UVC camera (FakeUvcDevice behind the
// V4l2Device seam): format choice, exact pixel conversion, controls, buffer
// cycling, timeout and unplugging. The real syscall path (open, ioctl through
// the kernel interface) is covered by test_v4l2_umockdev.cpp.
#include "hal/v4l2/pixel_convert.hpp"
#include "hal/v4l2/v4l2_camera.hpp"
#include "tests/hal/fake_uvc_device.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace stria::hal {
namespace {

using testing::FakeFrame;
using testing::FakeUvcDevice;
using namespace std::chrono_literals;

constexpr FakeUvcDevice::Format kYuyv{V4L2_PIX_FMT_YUYV, false};
constexpr FakeUvcDevice::Format kMjpeg{V4L2_PIX_FMT_MJPEG, true};
constexpr FakeUvcDevice::Format kH264{V4L2_PIX_FMT_H264, true};
constexpr FakeUvcDevice::Format kRgb24{V4L2_PIX_FMT_RGB24, false};
constexpr FakeUvcDevice::Format kBgr24{V4L2_PIX_FMT_BGR24, false};

// Exact BT.601 limited range YCbCr -> R'G'B' (Kr 0.299, Kb 0.114), rounded.
void referenceYuvToBgr(int y, int u, int v, int bgr[3])
{
    const double luma = 255.0 / 219.0 * (y - 16), cb = 255.0 / 224.0 * (u - 128), cr = 255.0 / 224.0 * (v - 128);
    const double r = luma + 2 * (1 - 0.299) * cr;
    const double b = luma + 2 * (1 - 0.114) * cb;
    const double g = (luma - 0.299 * r - 0.114 * b) / 0.587;  // from Y' = Kr R + Kg G + Kb B
    const double channels[3] = {b, g, r};
    for (int c = 0; c < 3; ++c) bgr[c] = int(std::clamp(std::lround(channels[c]), 0L, 255L));
}

struct Opened {
    FakeUvcDevice* device;
    std::unique_ptr<V4l2Camera> camera;
};

Opened openFake(std::vector<FakeUvcDevice::Format> formats, std::vector<std::pair<int, int>> sizes = {{4, 2}})
{
    auto device = std::make_unique<FakeUvcDevice>(std::move(formats), std::move(sizes));
    FakeUvcDevice* raw = device.get();
    auto camera = V4l2Camera::open(std::move(device));
    EXPECT_TRUE(camera.isOk()) << camera.message();
    return {raw, camera ? std::move(*camera) : nullptr};
}

// 4x2 YUYV: black, white, BT.601 red, a brighter pixel sharing red's chroma,
// two BT.601 blues, two greys.
const std::vector<std::uint8_t> kYuyvFrame = {16, 128, 235, 128, 81, 90, 145, 240,  // row 0
                                              41, 240, 41, 110, 126, 128, 127, 128};  // row 1

TEST(V4l2Camera, YuyvFrameBecomesExactBgrBytes)
{
    auto [device, camera] = openFake({kMjpeg, kYuyv});
    ASSERT_TRUE(camera);
    EXPECT_EQ(camera->pixelFormat(), V4L2_PIX_FMT_YUYV);
    ASSERT_TRUE(camera->configure({4, 2}).isOk());
    ASSERT_TRUE(camera->start().isOk());
    device->pushFrame({kYuyvFrame});
    auto frame = camera->capture(100ms);
    ASSERT_TRUE(frame.isOk()) << frame.message();
    ASSERT_EQ(frame->view.width, 4);
    ASSERT_EQ(frame->view.height, 2);
    const std::vector<std::uint8_t> expected = {0,   0, 0, 255, 255, 255, 0,   0,   255, 74,  74,  255,
                                                255, 0, 0, 255, 0,   0,   128, 128, 128, 129, 129, 129};
    std::vector<std::uint8_t> got;
    for (int y = 0; y < 2; ++y) got.insert(got.end(), frame->view.row(y), frame->view.row(y) + 12);
    EXPECT_EQ(got, expected);
}

TEST(V4l2Camera, YuyvConversionIsWithinOneLevelOfExactBt601)
{
    // Every Y with a grid of chroma values, one pixel pair per (Y, U, V).
    std::vector<std::uint8_t> yuyv, bgr;
    std::vector<int> reference;
    for (int y = 0; y < 256; ++y)
        for (int u = 0; u < 256; u += 5)
            for (int v = 0; v < 256; v += 5) {
                yuyv.insert(yuyv.end(), {std::uint8_t(y), std::uint8_t(u), std::uint8_t(y), std::uint8_t(v)});
                int expected[3];
                referenceYuvToBgr(y, u, v, expected);
                reference.insert(reference.end(), {expected[0], expected[1], expected[2], expected[0], expected[1],
                                                   expected[2]});
            }
    const int width = int(yuyv.size() / 2);
    bgr.resize(std::size_t(width) * 3);
    convertYuyvToBgr({yuyv.data(), width, 1, std::ptrdiff_t(yuyv.size()), PixelFormat::Yuyv},
                     {bgr.data(), width, 1, std::ptrdiff_t(bgr.size()), PixelFormat::Bgr8});
    int worst = 0, exact = 0;
    for (std::size_t i = 0; i < bgr.size(); ++i) {
        worst = std::max(worst, std::abs(int(bgr[i]) - reference[i]));
        exact += bgr[i] == reference[i];
    }
    EXPECT_LE(worst, 1);
    EXPECT_GT(double(exact) / double(bgr.size()), 0.9);  // fixed point rounds like the exact transform almost always
}

TEST(V4l2Camera, PrefersBgr24ThenRgb24ThenYuyv)
{
    EXPECT_EQ(openFake({kYuyv, kRgb24, kBgr24}).camera->pixelFormat(), V4L2_PIX_FMT_BGR24);
    EXPECT_EQ(openFake({kMjpeg, kYuyv, kRgb24}).camera->pixelFormat(), V4L2_PIX_FMT_RGB24);
}

TEST(V4l2Camera, Rgb24BecomesBgr)
{
    auto [device, camera] = openFake({kRgb24}, {{2, 1}});
    ASSERT_TRUE(camera->configure({2, 1}).isOk());
    ASSERT_TRUE(camera->start().isOk());
    device->pushFrame({{10, 20, 30, 40, 50, 60}});
    auto frame = camera->capture(100ms);
    ASSERT_TRUE(frame.isOk()) << frame.message();
    EXPECT_EQ(std::vector<std::uint8_t>(frame->view.data, frame->view.data + 6),
              (std::vector<std::uint8_t>{30, 20, 10, 60, 50, 40}));
}

TEST(V4l2Camera, CompressedOnlyCameraIsRefused)
{
    auto camera = V4l2Camera::open(std::make_unique<FakeUvcDevice>(std::vector{kMjpeg, kH264},
                                                                   std::vector<std::pair<int, int>>{{640, 480}}));
    ASSERT_FALSE(camera.isOk());
    EXPECT_EQ(camera.message(),
              "camera '/dev/video0' offers only compressed formats (MJPG, H264): stria needs YUYV, RGB24 or BGR24");
}

TEST(V4l2Camera, SizeTheDriverChangesIsRefusedNamingBothSizes)
{
    auto [device, camera] = openFake({kYuyv}, {{640, 480}, {1280, 720}});
    Status status = camera->configure({1600, 1200});
    ASSERT_FALSE(status.isOk());
    EXPECT_EQ(status.message(), "camera '/dev/video0' delivers YUYV 640x480 when asked for YUYV 1600x1200: pick a "
                                "size the camera supports (v4l2-ctl --list-formats-ext)");
    EXPECT_EQ(device->mappedBuffers(), 0);  // nothing mapped for a refused format
    EXPECT_TRUE(camera->configure({1280, 720}).isOk());
    EXPECT_EQ(device->mappedBuffers(), 3);
}

TEST(V4l2Camera, ManualExposureAndGainAreAppliedAndReported)
{
    auto [device, camera] = openFake({kYuyv});
    CameraConfig config{4, 2};
    config.exposureUs = 12'340;  // -> 123 units of 100 us, applied as 12300 us
    config.analogueGain = 2.0;   // the default gain (32) counts as 1.0x
    ASSERT_TRUE(camera->configure(config).isOk());
    EXPECT_EQ(device->controls()[V4L2_CID_EXPOSURE_AUTO].value, V4L2_EXPOSURE_MANUAL);
    EXPECT_EQ(device->controls()[V4L2_CID_AUTO_WHITE_BALANCE].value, 0);
    EXPECT_EQ(device->controls()[V4L2_CID_EXPOSURE_ABSOLUTE].value, 123);
    EXPECT_EQ(device->controls()[V4L2_CID_GAIN].value, 64);
    EXPECT_TRUE(camera->missingControls().empty());
    ASSERT_TRUE(camera->start().isOk());
    device->pushFrame({kYuyvFrame});
    auto frame = camera->capture(100ms);
    ASSERT_TRUE(frame.isOk()) << frame.message();
    EXPECT_DOUBLE_EQ(frame->exposureUs, 12'300);
    EXPECT_DOUBLE_EQ(frame->analogueGain, 2.0);
}

TEST(V4l2Camera, MissingControlsAreReportedAndOutOfRangeExposureRefused)
{
    auto [device, camera] = openFake({kYuyv});
    device->controls().erase(V4L2_CID_GAIN);
    device->controls().erase(V4L2_CID_AUTO_WHITE_BALANCE);
    ASSERT_TRUE(camera->configure({4, 2}).isOk());
    EXPECT_EQ(camera->missingControls(), (std::vector<std::string>{"white_balance_automatic", "gain"}));

    CameraConfig tooShort{4, 2};
    tooShort.exposureUs = 100;
    Status status = camera->configure(tooShort);
    EXPECT_EQ(status.message(), "camera '/dev/video0': exposure_time_absolute 1 is outside the camera's range 3..2047");
}

TEST(V4l2Camera, BuffersAreRequeuedAndCorruptFramesDropped)
{
    auto [device, camera] = openFake({kYuyv});
    ASSERT_TRUE(camera->configure({4, 2}).isOk());
    ASSERT_TRUE(camera->start().isOk());
    // Ten frames through three buffers: only works if each one goes back.
    for (int i = 0; i < 10; ++i) {
        device->pushFrame({kYuyvFrame, i == 4});
        if (i == 4) continue;
        auto frame = camera->capture(100ms);
        ASSERT_TRUE(frame.isOk()) << "frame " << i << ": " << frame.message();
        EXPECT_EQ(frame->sequence, std::uint64_t(i));
    }
}

TEST(V4l2Camera, TimestampIsTheStartOfExposure)
{
    auto [device, camera] = openFake({kYuyv});
    CameraConfig config{4, 2};
    config.exposureUs = 5'000;
    ASSERT_TRUE(camera->configure(config).isOk());
    ASSERT_TRUE(camera->start().isOk());
    device->pushFrame({kYuyvFrame});                      // UVC: stamped at the start of exposure
    device->pushFrame({kYuyvFrame, false, true});         // stamped when the frame ended
    auto first = camera->capture(100ms);
    ASSERT_TRUE(first.isOk()) << first.message();
    EXPECT_EQ(first->timestampNs, 100'000'000'000);
    auto second = camera->capture(100ms);
    ASSERT_TRUE(second.isOk()) << second.message();
    // 100 s + 33.333 ms, minus a frame period (1/30 s) and the 5 ms exposure.
    EXPECT_EQ(second->timestampNs, 100'033'333'000 - 33'333'333 - 5'000'000);
}

TEST(V4l2Camera, NoFrameGivesTimeoutError)
{
    auto [device, camera] = openFake({kYuyv});
    ASSERT_TRUE(camera->configure({4, 2}).isOk());
    ASSERT_TRUE(camera->start().isOk());
    auto frame = camera->capture(250ms);
    ASSERT_FALSE(frame.isOk());
    EXPECT_EQ(frame.message(), "camera '/dev/video0': no frame within 250 ms");
}

TEST(V4l2Camera, UnpluggedMidStreamGivesEnodevError)
{
    auto [device, camera] = openFake({kYuyv});
    ASSERT_TRUE(camera->configure({4, 2}).isOk());
    ASSERT_TRUE(camera->start().isOk());
    device->pushFrame({kYuyvFrame});
    ASSERT_TRUE(camera->capture(100ms).isOk());
    device->unplug();
    auto frame = camera->capture(100ms);
    ASSERT_FALSE(frame.isOk());
    EXPECT_EQ(frame.message(), "camera '/dev/video0': camera vanished during capture: No such device (the camera "
                               "was unplugged or its driver went away)");
}

TEST(V4l2Camera, MissingDeviceNamesPathAndCause)
{
    auto camera = V4l2Camera::open("/dev/video-stria-missing");
    ASSERT_FALSE(camera.isOk());
    EXPECT_EQ(camera.message(), "camera '/dev/video-stria-missing': cannot open: No such file or directory (is the "
                                "camera plugged in?)");
}

TEST(V4l2Camera, CaptureBeforeStartIsAnError)
{
    auto [device, camera] = openFake({kYuyv});
    ASSERT_TRUE(camera->configure({4, 2}).isOk());
    EXPECT_EQ(camera->capture(10ms).message(), "camera '/dev/video0': capture() before start()");
}

}  // namespace
}  // namespace stria::hal
