#pragma once
// Every difference between libcamera versions stria meets, in one place:
// Debian 12 ships libcamera 0.0.3, Raspberry Pi OS a newer fork.
//  - 0.2 replaced CameraConfiguration::transform by ::orientation.
//  - 0.5 removed AeEnable: manual exposure and gain are
//    ExposureTimeMode/AnalogueGainMode = Manual.
// ControlList::get() returns std::optional in every version we build with.

#include <libcamera/camera.h>
#include <libcamera/control_ids.h>
#include <libcamera/controls.h>
#include <libcamera/version.h>

#include <cmath>
#include <cstdint>
#include <optional>

#define STRIA_LIBCAMERA_AT_LEAST(major, minor) \
    (LIBCAMERA_VERSION_MAJOR > (major) || (LIBCAMERA_VERSION_MAJOR == (major) && LIBCAMERA_VERSION_MINOR >= (minor)))

namespace stria::hal::compat {

// Frames as the sensor sees them: the calibration was taken without flips.
inline void setIdentityOrientation(libcamera::CameraConfiguration& config)
{
#if STRIA_LIBCAMERA_AT_LEAST(0, 2)
    config.orientation = libcamera::Orientation::Rotate0;
#else
    config.transform = libcamera::Transform::Identity;
#endif
}

inline bool isIdentityOrientation(const libcamera::CameraConfiguration& config)
{
#if STRIA_LIBCAMERA_AT_LEAST(0, 2)
    return config.orientation == libcamera::Orientation::Rotate0;
#else
    return config.transform == libcamera::Transform::Identity;
#endif
}

// Fixed exposure time (us), fixed analogue gain, no auto white balance.
inline void setManualExposure(libcamera::ControlList& controls, double exposureUs, double analogueGain)
{
    namespace ctl = libcamera::controls;
#if STRIA_LIBCAMERA_AT_LEAST(0, 5)
    controls.set(ctl::ExposureTimeMode, ctl::ExposureTimeModeManual);
    controls.set(ctl::AnalogueGainMode, ctl::AnalogueGainModeManual);
#else
    controls.set(ctl::AeEnable, false);
#endif
    controls.set(ctl::AwbEnable, false);
    controls.set(ctl::ExposureTime, static_cast<std::int32_t>(std::lround(exposureUs)));
    controls.set(ctl::AnalogueGain, static_cast<float>(analogueGain));
}

struct AppliedExposure {
    std::optional<double> exposureUs, analogueGain;
    std::optional<std::int64_t> sensorTimestampNs;
};

// What a completed request's metadata says was applied.
inline AppliedExposure appliedExposure(const libcamera::ControlList& metadata)
{
    namespace ctl = libcamera::controls;
    AppliedExposure applied;
    if (auto exposure = metadata.get(ctl::ExposureTime)) applied.exposureUs = *exposure;
    if (auto gain = metadata.get(ctl::AnalogueGain)) applied.analogueGain = *gain;
    if (auto timestamp = metadata.get(ctl::SensorTimestamp)) applied.sensorTimestampNs = *timestamp;
    return applied;
}

}  // namespace stria::hal::compat
