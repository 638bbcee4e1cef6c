#pragma once
// Video mode: the LED stays on, the camera runs continuously and every frame
// that can be decoded is. Capture and decode overlap on two threads that
// share a fixed ring of frame slots, all allocated by create():
//
//   capture thread: camera.capture() -> copy into a free slot -> queued
//   decode thread:  oldest queued slot -> Decoder::decode() -> free again
//
// When the decoder falls behind and no slot is free, the capture thread
// overwrites the OLDEST queued frame: a live view wants the newest picture,
// and latency stays bounded by the ring. Each overwritten frame counts as
// dropped, so captured = decoded + dropped once run() has returned. Sensor
// frames the capture thread never collected (sequence gaps) count as missed;
// frames that started exposing before the LED was on are skipped uncounted.
//
// The LED goes off as soon as capturing ends (before the frames left in the
// ring are decoded), on every way out of run(), on requestStop() (a signal)
// and, if no frame arrives for light.max_on_ms, by the LedWatchdog that each
// captured frame re-arms.
#include "firmware/app/led_watchdog.hpp"
#include "hal/camera.hpp"
#include "hal/light.hpp"
#include "pipeline/decoder.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <vector>

namespace stria::firmware {

struct StreamOptions {
    int slots = 3;                     // frames in the ring (>= 2: one decoding, one filling)
    std::uint64_t maxFrames = 0;       // stop capturing after this many frames (0 = no limit)
    double maxSeconds = 0;             // stop capturing after this long (0 = no limit)
    double reportSeconds = 1.0;        // progress line period (0 = only the final summary)
    std::FILE* report = stderr;        // progress and summary lines go here (nullptr = nowhere)
    std::chrono::milliseconds captureTimeout{1000};
    std::chrono::milliseconds ledMaxGap{500};  // watchdog: LED off if no frame arrives for this long
};

struct StreamStats {
    std::uint64_t captured = 0;  // frames taken from the camera into the ring
    std::uint64_t decoded = 0;   // frames the decoder ran on (including failed decodes)
    std::uint64_t failed = 0;    // decodes that returned an error
    std::uint64_t dropped = 0;   // overwritten in the ring before being decoded
    std::uint64_t missed = 0;    // sensor frames never captured (gaps in the sequence numbers)
    std::uint64_t points = 0;    // points of all decoded frames
    double seconds = 0;          // from start to the last decode
    double decodeBusy = 0;       // fraction of `seconds` the decode thread spent decoding
    pipeline::StageTimings median;  // per stage, over the last kTimingWindow decodes

    double fps() const { return seconds > 0 ? static_cast<double>(decoded) / seconds : 0; }
};

struct StreamSummary {
    StreamStats stats;
    bool stopped = false;  // by requestStop()
    Status error;          // the camera or the LED failed and ended the stream
};

class Streamer {
public:
    static constexpr int kTimingWindow = 256;

    // Configures and starts the camera with `config` (its size must be the
    // decoder's) and allocates the ring. Camera, light and decoder are
    // borrowed and must outlive the Streamer.
    static Result<std::unique_ptr<Streamer>> create(hal::Camera& camera, hal::Light& light, pipeline::Decoder& decoder,
                                                    const hal::CameraConfig& config, const StreamOptions& options);
    ~Streamer();
    Streamer(const Streamer&) = delete;
    Streamer& operator=(const Streamer&) = delete;

    // Streams until maxFrames, maxSeconds, requestStop() or a camera error;
    // the frames already in the ring are decoded before it returns.
    StreamSummary run();
    // Async-signal-safe: LED off; run() ends within one capture timeout.
    void requestStop();

private:
    enum class SlotState : std::uint8_t { Free, Filling, Queued, Decoding };
    struct Slot {
        cv::Mat image;  // CV_8UC3, camera size
        SlotState state = SlotState::Free;
        std::uint64_t order = 0;  // capture count when queued: smallest = oldest
    };

    Streamer(hal::Camera& camera, hal::Light& light, pipeline::Decoder& decoder, const StreamOptions& options);
    void captureLoop();
    // The oldest slot in `state`, -1 if none. Caller holds mutex_.
    int oldest(SlotState state) const;
    void recordTimings(const pipeline::StageTimings& timings);
    pipeline::StageTimings medianTimings();
    void printStats(const char* label, const StreamStats& stats) const;

    hal::Camera& camera_;
    hal::Light& light_;
    pipeline::Decoder& decoder_;
    StreamOptions options_;
    std::unique_ptr<LedWatchdog> watchdog_;
    std::vector<Slot> slots_;

    std::mutex mutex_;  // guards slots_' states, stats_'s capture counts, captureDone_, error_
    std::condition_variable queued_;
    bool captureDone_ = false;
    Status error_;
    StreamStats stats_;
    std::atomic<bool> stop_{false};
    std::int64_t ledOnNs_ = 0;  // monotonic; frames exposed before it are skipped

    // Timings of the last kTimingWindow successful decodes (decode thread only).
    std::array<pipeline::StageTimings, kTimingWindow> timings_{};
    std::uint64_t timingCount_ = 0;
    std::array<double, kTimingWindow> medianScratch_{};
};

}  // namespace stria::firmware
