// Video mode end to end above the HAL: a ReplayCamera delivering pre-rendered
// 780x580 relief frames at a fixed rate, the capture/decode ring of Streamer
// and the decoder, for a fixed number of frames. Reports the decoded frames
// per second, the frames dropped in the ring and missed at the sensor, and
// how busy the decode thread was. The time is the stream's own wall time.
#include "tests/bench/bench_frames.hpp"

#include "firmware/app/stream.hpp"
#include "hal/sim/replay_camera.hpp"

#include <benchmark/benchmark.h>

#include <atomic>
#include <string>

namespace stria::bench {
namespace {

constexpr int kReplayFrames = 4;
constexpr double kStreamSeconds = 3;

// The projector LED as a flag: the stream only needs to switch it.
class LedFlag final : public hal::Light {
public:
    Status set(bool on) override
    {
        on_.store(on);
        return Status::ok();
    }
    bool isOn() const override { return on_.load(); }

private:
    std::atomic<bool> on_{false};
};

void stream(benchmark::State& state, int fps)
{
    const std::vector<cv::Mat>& frames = replayFrames(kReplayFrames);
    if (frames.empty()) {
        state.SkipWithError("the simulator could not render the replay frames");
        return;
    }
    const hal::sim::SimRig rig = hal::sim::desktopRig();
    auto decoder = pipeline::Decoder::create(rig.pattern, rig.rig);
    auto camera = hal::sim::ReplayCamera::create(frames, 1000000000LL / fps);
    if (!decoder || !camera) {
        state.SkipWithError((decoder ? camera.message() : decoder.message()).c_str());
        return;
    }
    LedFlag led;
    hal::CameraConfig config;
    config.width = frames.front().cols;
    config.height = frames.front().rows;
    firmware::StreamOptions options;
    options.maxFrames = static_cast<std::uint64_t>(kStreamSeconds * fps);
    options.report = nullptr;

    firmware::StreamStats total;
    for (auto _ : state) {
        auto streamer = firmware::Streamer::create(**camera, led, **decoder, config, options);
        if (!streamer) {
            state.SkipWithError(streamer.message().c_str());
            break;
        }
        const firmware::StreamSummary summary = (*streamer)->run();
        const firmware::StreamStats& s = summary.stats;
        if (!summary.error.isOk() || s.decoded + s.dropped != s.captured || s.captured != options.maxFrames ||
            s.failed > 0 || led.isOn()) {
            const std::string why = "stream broken: " + summary.error.message() + " captured " +
                                    std::to_string(s.captured) + ", decoded " + std::to_string(s.decoded) +
                                    ", dropped " + std::to_string(s.dropped) + ", failed " + std::to_string(s.failed);
            state.SkipWithError(why.c_str());
            break;
        }
        state.SetIterationTime(s.seconds);
        total.captured += s.captured;
        total.decoded += s.decoded;
        total.dropped += s.dropped;
        total.missed += s.missed;
        total.seconds += s.seconds;
        total.decodeBusy += s.decodeBusy * s.seconds;
        total.median = s.median;
    }
    if (total.seconds <= 0) return;
    auto& c = state.counters;
    c["fps"] = total.fps();
    c["target_fps"] = fps;
    c["dropped"] = static_cast<double>(total.dropped);
    c["missed"] = static_cast<double>(total.missed);
    c["captured"] = static_cast<double>(total.captured);
    c["decode_busy"] = total.decodeBusy / total.seconds;
    c["ms_decode_median"] = total.median.totalMs;
}

}  // namespace

BENCHMARK_CAPTURE(stream, 780x580_30fps, 30)->UseManualTime()->Iterations(1)->Repetitions(3)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(stream, 780x580_60fps, 60)->UseManualTime()->Iterations(1)->Repetitions(3)->Unit(benchmark::kMillisecond);

}  // namespace stria::bench
