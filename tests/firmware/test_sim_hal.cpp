// The simulated HAL: press scripts through the debouncer, the camera seeing
// the LED state at exposure time, fault injection, size checks.
#include "hal/clock.hpp"
#include "hal/sim/sim_button.hpp"
#include "hal/sim/sim_camera.hpp"
#include "hal/sim/sim_light.hpp"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <cstdio>
#include <memory>
#include <thread>

using namespace stria;
using namespace stria::hal;
using namespace std::chrono_literals;

namespace {

std::unique_ptr<sim::SimWorld> makeWorld()
{
    sim::SimRig rig = sim::desktopRig();
    sim::Scene scene = sim::makeScene(sim::SceneKind::TiltedPlane, rig, sim::Albedo::Uniform, 1);
    sim::RenderSettings render;
    render.samplesPerPixel = 1;
    return std::make_unique<sim::SimWorld>(std::move(rig), std::move(scene), render);
}

int countPresses(sim::SimButton& button)
{
    int presses = 0;
    for (;;) {
        auto wait = button.waitForPress(10s);
        EXPECT_TRUE(wait.isOk());
        if (!wait || *wait != ButtonWait::Pressed) return presses;
        ++presses;
    }
}

// Mean absolute difference between horizontally adjacent pixels: large with
// stripes (every ~7 px a colour edge), small without.
double horizontalVariation(const FrameView& view)
{
    const cv::Mat image(view.height, view.width, CV_8UC3, const_cast<std::uint8_t*>(view.data),
                        static_cast<std::size_t>(view.stride));
    cv::Mat diff;
    cv::absdiff(image.colRange(1, image.cols), image.colRange(0, image.cols - 1), diff);
    const cv::Scalar m = cv::mean(diff);
    return (m[0] + m[1] + m[2]) / 3;
}

}  // namespace

TEST(PressScript, ParsesAndRejects)
{
    auto presses = sim::parsePressScript("100, 900b,1500");
    ASSERT_TRUE(presses.isOk()) << presses.message();
    ASSERT_EQ(presses->size(), 3u);
    EXPECT_EQ((*presses)[1].timeMs, 900);
    EXPECT_TRUE((*presses)[1].bounce);
    EXPECT_FALSE((*presses)[2].bounce);
    EXPECT_TRUE(sim::parsePressScript("")->empty());
    EXPECT_EQ(sim::parsePressScript("100,x").message(),
              "press script '100,x': 'x' is not a time in ms (optionally followed by b for bounce)");
    EXPECT_EQ(sim::parsePressScript("500,100").message(), "press script '500,100': times must not decrease (100 after 500)");
}

TEST(SimButton, EveryScriptedPressOnceAndBounceGivesOnePress)
{
    sim::SimButton plain(*sim::parsePressScript("100,900,1500"), 20, false);
    EXPECT_EQ(countPresses(plain), 3);
    sim::SimButton bouncy(*sim::parsePressScript("100b,900b"), 20, false);
    EXPECT_EQ(countPresses(bouncy), 2);
    // Without debouncing every chatter of a bouncing contact counts: three
    // closures while pressing, two more while releasing.
    sim::SimButton raw(*sim::parsePressScript("100b"), 0, false);
    EXPECT_EQ(countPresses(raw), 5);
}

TEST(SimButton, TimesOutAndIsInterrupted)
{
    sim::SimButton button(*sim::parsePressScript("5000"), 20, false);
    auto first = button.waitForPress(1000ms);
    ASSERT_TRUE(first.isOk());
    EXPECT_EQ(*first, ButtonWait::TimedOut);
    button.interrupt();
    EXPECT_EQ(*button.waitForPress(10s), ButtonWait::Interrupted);
    EXPECT_EQ(*button.waitForPress(10s), ButtonWait::Pressed);  // the interrupt was consumed
    EXPECT_EQ(*button.waitForPress(10s), ButtonWait::Interrupted);  // script used up
}

TEST(SimButton, RealTimeWaitsForThePressAndWakesOnInterrupt)
{
    sim::SimButton button(*sim::parsePressScript("80,100000"), 20, true);
    const std::int64_t start = monotonicNs();
    EXPECT_EQ(*button.waitForPress(5s), ButtonWait::Pressed);
    const double pressedAfterMs = static_cast<double>(monotonicNs() - start) / 1e6;
    EXPECT_GE(pressedAfterMs, 100.0 - 1);  // 80 ms + 20 ms debounce
    std::thread waker([&] {
        std::this_thread::sleep_for(50ms);
        button.interrupt();
    });
    const std::int64_t waitStart = monotonicNs();
    EXPECT_EQ(*button.waitForPress(5s), ButtonWait::Interrupted);
    EXPECT_LT(static_cast<double>(monotonicNs() - waitStart) / 1e6, 2000.0);
    waker.join();
}

TEST(SimCamera, SeesTheLedStateDuringTheExposure)
{
    // Back-to-back 20 ms exposures: frame n exposes [n * 20 ms, (n + 1) * 20 ms).
    // The LED goes on in the middle of the frame after a dark one: that frame
    // is only partly lit and must not show stripes, the one after it must.
    // The scenario needs this thread to run on time (the switch 10 ms inside
    // its frame, each capture() before its frame ends); on a loaded machine
    // the scheduler can miss that by tens of milliseconds, and the camera
    // then rightly delivers other frames. Such an attempt is detected from
    // the times the camera reports and run again on a fresh world: what is
    // asserted is the camera's behaviour, not the scheduler's.
    constexpr int kAttempts = 5;
    int attempt = 0;
    for (; attempt < kAttempts; ++attempt) {
        auto world = makeWorld();
        sim::SimLight light(*world);
        sim::SimCamera camera(*world, 20000);
        ASSERT_TRUE(camera.configure(CameraConfig{780, 580, 20000, 1.0, 3}));
        ASSERT_TRUE(camera.start());

        auto dark = camera.capture(200ms);
        ASSERT_TRUE(dark.isOk()) << dark.message();
        const double darkVariation = horizontalVariation(dark->view);
        const std::uint64_t darkSequence = dark->sequence;

        sleepUntilNs(dark->timestampNs + 30'000'000);
        ASSERT_TRUE(light.set(true));
        EXPECT_TRUE(light.isOn());
        const std::int64_t onAt = monotonicNs();
        auto partly = camera.capture(200ms);
        ASSERT_TRUE(partly.isOk());
        auto lit = camera.capture(200ms);
        ASSERT_TRUE(lit.isOk());
        ASSERT_TRUE(light.set(false));

        // On time: the switch fell inside frame n + 1's exposure and both
        // captures got the next frames.
        const bool onTime = onAt < dark->timestampNs + 40'000'000 && partly->sequence == darkSequence + 1 &&
                            lit->sequence == darkSequence + 2;
        if (!onTime) {
            std::printf("attempt %d: the scheduler missed the window (LED on %.1f ms into the dark frame, "
                        "frames %llu and %llu after it); again\n",
                        attempt + 1, static_cast<double>(onAt - dark->timestampNs) / 1e6,
                        static_cast<unsigned long long>(partly->sequence - darkSequence),
                        static_cast<unsigned long long>(lit->sequence - darkSequence));
            continue;
        }
        EXPECT_LT(partly->timestampNs, onAt);
        EXPECT_NEAR(horizontalVariation(partly->view), darkVariation, 1e-9);
        EXPECT_GE(lit->timestampNs, onAt);
        EXPECT_GT(horizontalVariation(lit->view), 4 * darkVariation);
        EXPECT_DOUBLE_EQ(lit->exposureUs, 20000);
        EXPECT_EQ(camera.renderCount(), 2);  // both looks rendered once, at configure()

        const auto log = world->ledLog();
        ASSERT_EQ(log.size(), 2u);
        EXPECT_TRUE(log[0].on);
        EXPECT_FALSE(log[1].on);
        EXPECT_LE(log[0].timeNs, onAt);
        break;
    }
    EXPECT_LT(attempt, kAttempts) << "the scheduler missed the 10 ms window in all " << kAttempts << " attempts";
}

TEST(SimCamera, SizeMismatchAndTimeouts)
{
    auto world = makeWorld();
    sim::SimCamera camera(*world, 5000);
    EXPECT_EQ(camera.configure(CameraConfig{640, 480}).message(),
              "camera 'sim': requested 640x480 but the simulated sensor delivers 780x580");
    EXPECT_EQ(camera.capture(10ms).message(), "camera 'sim': capture() while not streaming (call start())");
    ASSERT_TRUE(camera.configure(CameraConfig{780, 580, 2000}));
    ASSERT_TRUE(camera.start());
    world->injectCaptureTimeouts(1);
    const std::int64_t start = monotonicNs();
    EXPECT_EQ(camera.capture(50ms).message(), "camera 'sim': no frame within 50 ms");
    EXPECT_GE(monotonicNs() - start, 50'000'000);
    EXPECT_TRUE(camera.capture(50ms).isOk());
    // A frame interval longer than the timeout cannot deliver in time.
    sim::SimCamera slow(*world, 500000);
    ASSERT_TRUE(slow.configure(CameraConfig{780, 580, 2000}));
    ASSERT_TRUE(slow.start());
    ASSERT_TRUE(slow.capture(100ms).isOk());  // frame 0 ends 2 ms after start
    EXPECT_EQ(slow.capture(100ms).message(), "camera 'sim': no frame within 100 ms");
}
