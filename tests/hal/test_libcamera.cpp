// The libcamera backend without a camera: opening reports the missing camera
// clearly (the CameraManager starts fine in a container), and the version
// compatibility layer sets and reads the controls the backend relies on.
#include "hal/libcamera/compat.hpp"
#include "hal/libcamera/libcamera_camera.hpp"

#include <gtest/gtest.h>

namespace stria::hal {
namespace {

namespace ctl = libcamera::controls;

TEST(LibcameraCamera, NoCameraGivesAClearMessage)
{
    auto camera = LibcameraCamera::open("");
    ASSERT_FALSE(camera.isOk());
    EXPECT_EQ(camera.message(), "no libcamera camera found (check the sensor's dtoverlay in config.txt; `cam --list` "
                                "shows what libcamera sees)");
    EXPECT_EQ(LibcameraCamera::open("/base/soc/i2c0mux/i2c@1/imx219@10").message(), camera.message());
}

TEST(LibcameraCamera, ExposureToleranceAllowsLineQuantisationOnly)
{
    EXPECT_TRUE(exposureMatches(10'000, 10'150));   // 1.5 %
    EXPECT_FALSE(exposureMatches(10'000, 10'250));  // 2.5 %: not yet applied
    EXPECT_TRUE(exposureMatches(1'000, 1'090));     // short exposures: within 100 us
    EXPECT_FALSE(exposureMatches(1'000, 1'150));
    EXPECT_FALSE(exposureMatches(10'000, 33'000));  // still the auto exposure's choice
}

TEST(LibcameraCompat, ManualExposureControls)
{
    libcamera::ControlList controls(ctl::controls);
    compat::setManualExposure(controls, 12'345.6, 2.5);
    EXPECT_EQ(controls.get(ctl::ExposureTime).value_or(-1), 12'346);
    EXPECT_FLOAT_EQ(controls.get(ctl::AnalogueGain).value_or(-1.0f), 2.5f);
    EXPECT_EQ(controls.get(ctl::AwbEnable).value_or(true), false);
#if STRIA_LIBCAMERA_AT_LEAST(0, 5)
    EXPECT_EQ(controls.get(ctl::ExposureTimeMode).value_or(-1), ctl::ExposureTimeModeManual);
#else
    EXPECT_EQ(controls.get(ctl::AeEnable).value_or(true), false);
#endif
}

TEST(LibcameraCompat, AppliedExposureFromMetadata)
{
    libcamera::ControlList metadata(ctl::controls);
    compat::AppliedExposure none = compat::appliedExposure(metadata);
    EXPECT_FALSE(none.exposureUs || none.analogueGain || none.sensorTimestampNs);

    metadata.set(ctl::ExposureTime, 9'987);
    metadata.set(ctl::AnalogueGain, 1.5f);
    metadata.set(ctl::SensorTimestamp, std::int64_t(123'456'789'000));
    compat::AppliedExposure applied = compat::appliedExposure(metadata);
    EXPECT_DOUBLE_EQ(applied.exposureUs.value_or(0), 9'987);
    EXPECT_DOUBLE_EQ(applied.analogueGain.value_or(0), 1.5);
    EXPECT_EQ(applied.sensorTimestampNs.value_or(0), 123'456'789'000);
}

class FixedConfiguration : public libcamera::CameraConfiguration {
public:
    Status validate() override { return Valid; }
};

TEST(LibcameraCompat, IdentityOrientation)
{
    FixedConfiguration config;
#if STRIA_LIBCAMERA_AT_LEAST(0, 2)
    config.orientation = libcamera::Orientation::Rotate180;
#else
    config.transform = libcamera::Transform::Rot180;
#endif
    EXPECT_FALSE(compat::isIdentityOrientation(config));
    compat::setIdentityOrientation(config);
    EXPECT_TRUE(compat::isIdentityOrientation(config));
}

}  // namespace
}  // namespace stria::hal
