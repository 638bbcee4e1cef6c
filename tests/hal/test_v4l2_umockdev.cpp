// V4l2Camera through the real system calls (openV4l2Device: open() and
// ioctl() on a device node) in a umockdev testbed: data/usb-endoscope.umockdev
// describes the camera's sysfs and /dev/video0 node, and umockdev forwards
// every ioctl on that node to the same emulated UVC camera the other V4L2
// tests use. umockdev cannot emulate mmap(), so these tests stop before
// streaming: they cover open (QUERYCAP, ENUM_FMT) and S_FMT/controls.
// Runs under umockdev-wrapper (see CMakeLists.txt).
#include "hal/v4l2/v4l2_camera.hpp"
#include "tests/hal/fake_uvc_device.hpp"

#include <gtest/gtest.h>
#include <umockdev.h>

#include <sys/ioctl.h>

#include <cstdlib>
#include <cstring>

namespace stria::hal {
namespace {

using testing::FakeUvcDevice;

// Runs in umockdev's worker thread: resolves the ioctl argument into local
// memory, lets the emulated camera act on it, and completes the call.
gboolean forwardIoctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer camera)
{
    const gulong request = umockdev_ioctl_client_get_request(client);
    GError* error = nullptr;
    UMockdevIoctlData* data =
        umockdev_ioctl_data_resolve(umockdev_ioctl_client_get_arg(client), 0, _IOC_SIZE(request), &error);
    if (!data) {
        g_error_free(error);
        umockdev_ioctl_client_complete(client, -1, EFAULT);
        return TRUE;
    }
    const int result = static_cast<FakeUvcDevice*>(camera)->ioctl(request, data->data);
    umockdev_ioctl_client_complete(client, result < 0 ? -1 : 0, result < 0 ? -result : 0);
    g_object_unref(data);
    return TRUE;
}

class V4l2Umockdev : public ::testing::Test {
protected:
    void SetUp() override
    {
        // umockdev_in_mock_environment() looks for the preload library through
        // dladdr(open), which misses it in PIE test binaries: check the variable.
        const char* preload = std::getenv("LD_PRELOAD");
        ASSERT_TRUE(preload && std::strstr(preload, "libumockdev-preload")) << "run this test under umockdev-wrapper";
        testbed_ = umockdev_testbed_new();
        GError* error = nullptr;
        ASSERT_TRUE(umockdev_testbed_add_from_file(testbed_, STRIA_SOURCE_DIR "/tests/hal/data/usb-endoscope.umockdev",
                                                   &error))
            << error->message;
    }

    void TearDown() override
    {
        if (handler_) g_object_unref(handler_);
        if (testbed_) g_object_unref(testbed_);
    }

    void attach(FakeUvcDevice& camera)
    {
        handler_ = umockdev_ioctl_base_new();
        g_signal_connect(handler_, "handle-ioctl", G_CALLBACK(forwardIoctl), &camera);
        GError* error = nullptr;
        ASSERT_TRUE(umockdev_testbed_attach_ioctl(testbed_, "/dev/video0", handler_, &error)) << error->message;
    }

    UMockdevTestbed* testbed_ = nullptr;
    UMockdevIoctlBase* handler_ = nullptr;
};

TEST_F(V4l2Umockdev, OpensTheNodeAndPicksYuyvOverMjpeg)
{
    FakeUvcDevice camera({{V4L2_PIX_FMT_MJPEG, true}, {V4L2_PIX_FMT_YUYV, false}}, {{640, 480}});
    attach(camera);
    auto opened = V4l2Camera::open("/dev/video0");
    ASSERT_TRUE(opened.isOk()) << opened.message();
    EXPECT_EQ((*opened)->pixelFormat(), V4L2_PIX_FMT_YUYV);
}

TEST_F(V4l2Umockdev, CompressedOnlyCameraIsRefused)
{
    FakeUvcDevice camera({{V4L2_PIX_FMT_MJPEG, true}}, {{640, 480}});
    attach(camera);
    auto opened = V4l2Camera::open("/dev/video0");
    ASSERT_FALSE(opened.isOk());
    EXPECT_EQ(opened.message(),
              "camera '/dev/video0' offers only compressed formats (MJPG): stria needs YUYV, RGB24 or BGR24");
}

TEST_F(V4l2Umockdev, DriverAdjustedSizeIsRefusedBeforeAnyControlIsTouched)
{
    FakeUvcDevice camera({{V4L2_PIX_FMT_YUYV, false}}, {{640, 480}});
    attach(camera);
    auto opened = V4l2Camera::open("/dev/video0");
    ASSERT_TRUE(opened.isOk()) << opened.message();
    Status status = (*opened)->configure({1280, 720});
    EXPECT_EQ(status.message(), "camera '/dev/video0' delivers YUYV 640x480 when asked for YUYV 1280x720: pick a "
                                "size the camera supports (v4l2-ctl --list-formats-ext)");
    EXPECT_EQ(camera.controls()[V4L2_CID_EXPOSURE_AUTO].value, 3);  // still aperture priority
}

TEST_F(V4l2Umockdev, NodeWithoutIoctlsIsNotAV4l2Device)
{
    // The node exists but nothing answers its ioctls (a wrong path in the
    // board file, e.g. a serial port): umockdev fails them with ENOTTY.
    auto opened = V4l2Camera::open("/dev/video0");
    ASSERT_FALSE(opened.isOk());
    EXPECT_EQ(opened.message(),
              "camera '/dev/video0': not a V4L2 device (VIDIOC_QUERYCAP): Inappropriate ioctl for device");
}

}  // namespace
}  // namespace stria::hal
