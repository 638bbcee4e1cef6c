// Streamer over a ReplayCamera of simulator frames: every captured frame is
// decoded or counted as dropped, steady-state streaming allocates nothing
// (global operator new and the C allocator are replaced in this binary and
// count), and the LED is on while streaming and off on every way out.
#include "tests/support/allocation_counter.hpp"
#include "firmware/app/stop_signals.hpp"
#include "firmware/app/stream.hpp"
#include "hal/clock.hpp"
#include "hal/sim/replay_camera.hpp"
#include "hal/sim/sim_light.hpp"

#include <gtest/gtest.h>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <new>
#include <thread>

namespace stria {
namespace {

using namespace std::chrono_literals;
using firmware::StreamOptions;
using firmware::Streamer;
using firmware::StreamSummary;

constexpr std::int64_t kMs = 1000000;

// The desktop rig's relief, cheap to render (1 sample per pixel), noise 2;
// the LED is a SimLight, so its changes are logged with their times.
class StreamTest : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        hal::sim::SimRig rig = hal::sim::desktopRig();
        hal::sim::Scene scene =
            hal::sim::makeScene(hal::sim::SceneKind::TexturedRelief, rig, hal::sim::Albedo::Coloured, 3);
        hal::sim::RenderSettings render;
        render.noiseSigma = 2;
        render.samplesPerPixel = 1;
        world_ = new hal::sim::SimWorld(std::move(rig), std::move(scene), render);
        auto frames = hal::sim::renderReplayFrames(*world_, 3, 10000, 1.0);
        ASSERT_TRUE(frames) << frames.message();
        frames_ = new std::vector<cv::Mat>(std::move(*frames));
    }
    static void TearDownTestSuite()
    {
        delete frames_;
        delete world_;
    }

    void SetUp() override
    {
        auto decoder = pipeline::Decoder::create(world_->rig().pattern, world_->rig().rig);
        ASSERT_TRUE(decoder) << decoder.message();
        decoder_ = std::move(*decoder);
        config_.width = frames_->front().cols;
        config_.height = frames_->front().rows;
        options_.report = nullptr;
    }

    std::unique_ptr<hal::sim::ReplayCamera> camera(std::int64_t intervalNs) const
    {
        auto camera = hal::sim::ReplayCamera::create(*frames_, intervalNs);
        EXPECT_TRUE(camera) << camera.message();
        return camera ? std::move(*camera) : nullptr;
    }

    // The LED changes logged since `sinceNs`.
    static std::vector<hal::sim::LedEvent> ledChangesSince(std::int64_t sinceNs)
    {
        std::vector<hal::sim::LedEvent> events;
        for (const auto& e : world_->ledLog())
            if (e.timeNs >= sinceNs) events.push_back(e);
        return events;
    }

    static hal::sim::SimWorld* world_;
    static std::vector<cv::Mat>* frames_;
    hal::sim::SimLight light_{*world_};
    std::unique_ptr<pipeline::Decoder> decoder_;
    hal::CameraConfig config_;
    StreamOptions options_;
};

hal::sim::SimWorld* StreamTest::world_ = nullptr;
std::vector<cv::Mat>* StreamTest::frames_ = nullptr;

TEST_F(StreamTest, AFastCameraFillsTheRingAndEveryFrameIsDecodedOrDropped)
{
    // A camera with no frame interval outruns any decoder: the ring overflows.
    auto cam = camera(0);
    options_.maxFrames = 300;
    const std::int64_t startNs = hal::monotonicNs();
    auto streamer = Streamer::create(*cam, light_, *decoder_, config_, options_);
    ASSERT_TRUE(streamer) << streamer.message();
    const StreamSummary summary = (*streamer)->run();

    ASSERT_TRUE(summary.error.isOk()) << summary.error.message();
    EXPECT_FALSE(summary.stopped);
    EXPECT_EQ(summary.stats.captured, 300u);
    EXPECT_EQ(summary.stats.decoded + summary.stats.dropped, summary.stats.captured);
    EXPECT_GT(summary.stats.dropped, 0u);
    EXPECT_GE(summary.stats.decoded, 2u);
    EXPECT_EQ(summary.stats.failed, 0u);
    EXPECT_EQ(summary.stats.missed, 0u);  // interval 0: no sensor frame passes uncollected
    EXPECT_GT(summary.stats.points, 1000u * summary.stats.decoded);
    EXPECT_GT(summary.stats.median.totalMs, 0.0);
    // Off at create, on once for the whole stream, then only off.
    const auto changes = ledChangesSince(startNs);
    ASSERT_GE(changes.size(), 3u);
    EXPECT_FALSE(changes[0].on);
    EXPECT_TRUE(changes[1].on);
    EXPECT_EQ(std::count_if(changes.begin(), changes.end(), [](const auto& e) { return e.on; }), 1);
    EXPECT_FALSE(light_.isOn());
}

TEST_F(StreamTest, ARingWithRoomLosesNothing)
{
    // Five slots for four frames: however slow the decoder (qemu), no frame
    // ever has to be overwritten, and 100 ms between frames leave the capture
    // thread time to collect every one.
    auto cam = camera(100 * kMs);
    options_.slots = 5;
    options_.maxFrames = 4;
    auto streamer = Streamer::create(*cam, light_, *decoder_, config_, options_);
    ASSERT_TRUE(streamer) << streamer.message();
    const StreamSummary summary = (*streamer)->run();

    ASSERT_TRUE(summary.error.isOk()) << summary.error.message();
    EXPECT_EQ(summary.stats.captured, 4u);
    EXPECT_EQ(summary.stats.decoded, 4u);
    EXPECT_EQ(summary.stats.dropped, 0u);
    EXPECT_EQ(summary.stats.missed, 0u);
    EXPECT_GT(summary.stats.decodeBusy, 0.0);
    EXPECT_LT(summary.stats.decodeBusy, 1.0);
}

TEST_F(StreamTest, SteadyStateStreamingAllocatesNothingPerFrame)
{
    if (!test::kCountingAllocations) GTEST_SKIP() << "sanitizer build: the allocator is the sanitizer's";
    // Two runs that differ only in their length: everything run() allocates
    // (its thread) is allocated once per run, so the longer run must not
    // allocate more. The ring holds every frame, so all are decoded whatever
    // the machine's speed. Progress lines go to /dev/null every millisecond,
    // so that path runs too.
    std::FILE* devNull = std::fopen("/dev/null", "w");
    ASSERT_NE(devNull, nullptr);
    options_.report = devNull;
    options_.reportSeconds = 0.001;
    auto runCounting = [&](std::uint64_t frames, StreamSummary& summary) {
        auto cam = camera(0);
        options_.slots = static_cast<int>(frames) + 1;
        options_.maxFrames = frames;
        auto streamer = Streamer::create(*cam, light_, *decoder_, config_, options_);
        EXPECT_TRUE(streamer) << streamer.message();
        if (!streamer) return -1L;
        const long before = test::allocationCount();
        summary = (*streamer)->run();
        return test::allocationCount() - before;
    };
    // A first run pays for what the C library allocates on first use (stdio buffers).
    StreamSummary warmUp, shortRun, longRun;
    runCounting(2, warmUp);
    const long shortAllocations = runCounting(4, shortRun);
    const long longAllocations = runCounting(20, longRun);
    std::fclose(devNull);

    ASSERT_TRUE(shortRun.error.isOk() && longRun.error.isOk()) << longRun.error.message();
    ASSERT_EQ(shortRun.stats.decoded, 4u);
    ASSERT_EQ(longRun.stats.decoded, 20u);
    EXPECT_EQ(longAllocations, shortAllocations)
        << (longAllocations - shortAllocations) << " allocations for "
        << (longRun.stats.captured - shortRun.stats.captured) << " more frames";
}

TEST_F(StreamTest, SigtermStopsTheStreamCleanlyWithTheLedOff)
{
    auto cam = camera(20 * kMs);  // no frame or time limit: only the signal ends it
    auto streamer = Streamer::create(*cam, light_, *decoder_, config_, options_);
    ASSERT_TRUE(streamer) << streamer.message();
    std::atomic<bool> ledWasOn{false};
    StreamSummary summary;
    {
        const firmware::StopSignals signals(**streamer);
        std::thread killer([&] {
            std::this_thread::sleep_for(400ms);
            ledWasOn.store(light_.isOn());
            kill(getpid(), SIGTERM);
        });
        summary = (*streamer)->run();
        killer.join();
        EXPECT_EQ(firmware::StopSignals::received(), SIGTERM);
    }
    EXPECT_TRUE(ledWasOn.load());
    EXPECT_TRUE(summary.stopped);
    EXPECT_TRUE(summary.error.isOk()) << summary.error.message();
    EXPECT_FALSE(light_.isOn());
    EXPECT_GE(summary.stats.captured, 5u);
    EXPECT_EQ(summary.stats.decoded + summary.stats.dropped, summary.stats.captured);
}

TEST_F(StreamTest, ACameraTimeoutEndsTheStreamWithItsMessageAndTheLedOff)
{
    // Frame 0 was exposed before the LED came on (skipped), frame 1 comes
    // only after 5 s: the 100 ms wait times out.
    auto cam = camera(5000 * kMs);
    options_.captureTimeout = 100ms;
    auto streamer = Streamer::create(*cam, light_, *decoder_, config_, options_);
    ASSERT_TRUE(streamer) << streamer.message();
    const StreamSummary summary = (*streamer)->run();
    EXPECT_EQ(summary.error.message(), "camera 'replay': no frame within 100 ms");
    EXPECT_EQ(summary.stats.captured, 0u);
    EXPECT_EQ(summary.stats.decoded, 0u);
    EXPECT_FALSE(light_.isOn());
}

TEST_F(StreamTest, TheWatchdogSwitchesTheLedOffWhenFramesStopComing)
{
    // Frames every 300 ms but the LED may go 50 ms without one. Frame 0 was
    // exposed before the LED came on and is skipped; frame 1 comes too late.
    auto cam = camera(300 * kMs);
    options_.ledMaxGap = 50ms;
    auto streamer = Streamer::create(*cam, light_, *decoder_, config_, options_);
    ASSERT_TRUE(streamer) << streamer.message();
    const std::int64_t startNs = hal::monotonicNs();
    const StreamSummary summary = (*streamer)->run();
    EXPECT_EQ(summary.error.message(), "the LED was forced off after 50 ms without a frame");
    EXPECT_EQ(summary.stats.captured, 0u);
    EXPECT_FALSE(light_.isOn());
    // The watchdog's own switch-off came ~50 ms after the LED went on, long before frame 1.
    const auto changes = ledChangesSince(startNs);
    ASSERT_GE(changes.size(), 2u);
    EXPECT_TRUE(changes[0].on);
    EXPECT_FALSE(changes[1].on);
    EXPECT_LT(changes[1].timeNs - changes[0].timeNs, 250 * kMs);
}

TEST_F(StreamTest, StartupErrorsNameTheProblem)
{
    auto cam = camera(0);
    options_.slots = 1;
    auto oneSlot = Streamer::create(*cam, light_, *decoder_, config_, options_);
    ASSERT_FALSE(oneSlot);
    EXPECT_EQ(oneSlot.message(), "stream: 1 frame slots: at least 2 are needed (one decoding, one filling)");

    options_.slots = 3;
    hal::CameraConfig wrong = config_;
    wrong.width = 640;
    wrong.height = 480;
    auto wrongSize = Streamer::create(*cam, light_, *decoder_, wrong, options_);
    ASSERT_FALSE(wrongSize);
    EXPECT_EQ(wrongSize.message(), "camera 'replay': requested 640x480 but the replayed frames are 780x580");

    auto noFrames = hal::sim::ReplayCamera::create({}, 0);
    ASSERT_FALSE(noFrames);
    EXPECT_EQ(noFrames.message(), "camera 'replay': no frames to replay");
}

}  // namespace
}  // namespace stria
