#include "firmware/app/stream.hpp"

#include "hal/clock.hpp"

#include <algorithm>
#include <cstring>
#include <string>
#include <thread>

namespace stria::firmware {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The stage fields of StageTimings, in pipeline order, with their names.
constexpr std::array<double pipeline::StageTimings::*, 8> kStages{
    &pipeline::StageTimings::gradientMs, &pipeline::StageTimings::watershedMs, &pipeline::StageTimings::regionsMs,
    &pipeline::StageTimings::graphMs,    &pipeline::StageTimings::edgesMs,     &pipeline::StageTimings::decodeMs,
    &pipeline::StageTimings::depthMs,    &pipeline::StageTimings::totalMs};

}  // namespace

Streamer::Streamer(hal::Camera& camera, hal::Light& light, pipeline::Decoder& decoder, const StreamOptions& options) :
    camera_(camera), light_(light), decoder_(decoder), options_(options)
{
}

Streamer::~Streamer()
{
    watchdog_.reset();
    (void)light_.set(false);
    camera_.stop();
}

Result<std::unique_ptr<Streamer>> Streamer::create(hal::Camera& camera, hal::Light& light, pipeline::Decoder& decoder,
                                                   const hal::CameraConfig& config, const StreamOptions& options)
{
    if (options.slots < 2)
        return Status::error("stream: " + std::to_string(options.slots) +
                             " frame slots: at least 2 are needed (one decoding, one filling)");
    if (!(options.maxSeconds >= 0) || !(options.reportSeconds >= 0))
        return Status::error("stream: the time limit and the report period must be >= 0 s");
    if (options.ledMaxGap.count() <= 0) return Status::error("stream: the LED watchdog period must be > 0 ms");
    std::unique_ptr<Streamer> streamer(new Streamer(camera, light, decoder, options));
    // The LED starts off whatever state the line was left in.
    if (Status s = light.set(false); !s) return s.withContext("light: ");
    streamer->slots_.resize(static_cast<std::size_t>(options.slots));
    for (Slot& slot : streamer->slots_) slot.image.create(config.height, config.width, CV_8UC3);
    if (Status s = camera.configure(config); !s) return s;
    if (Status s = camera.start(); !s) return s;
    streamer->watchdog_ = std::make_unique<LedWatchdog>(light, options.ledMaxGap);
    return streamer;
}

void Streamer::requestStop()
{
    stop_.store(true);
    (void)light_.set(false);
}

int Streamer::oldest(SlotState state) const
{
    int best = -1;
    for (int i = 0; i < static_cast<int>(slots_.size()); ++i)
        if (slots_[i].state == state && (best < 0 || slots_[i].order < slots_[best].order)) best = i;
    return best;
}

void Streamer::captureLoop()
{
    const Clock::time_point start = Clock::now();
    const int width = slots_.front().image.cols, height = slots_.front().image.rows;
    std::uint64_t captured = 0, nextSequence = 0;
    Status error;
    while (!stop_.load()) {
        if (options_.maxFrames > 0 && captured >= options_.maxFrames) break;
        if (options_.maxSeconds > 0 && secondsSince(start) >= options_.maxSeconds) break;
        auto frame = camera_.capture(options_.captureTimeout);
        if (stop_.load()) break;  // the wait may have ended because of the stop
        if (!frame) {
            error = frame.status();
            break;
        }
        // Checked before re-arming, which clears it.
        if (watchdog_->fired()) {
            error = Status::error("the LED was forced off after " + std::to_string(options_.ledMaxGap.count()) +
                                  " ms without a frame");
            break;
        }
        watchdog_->arm();
        // Started exposing before the LED was on (a queued buffer, a
        // free-running sensor): unlit, not worth a slot.
        if (frame->timestampNs < ledOnNs_) continue;
        const FrameView& view = frame->view;
        if (view.width != width || view.height != height || view.format != PixelFormat::Bgr8) {
            error = Status::error(std::string("camera '") + camera_.backendName() + "' delivered a " +
                                  std::to_string(view.width) + "x" + std::to_string(view.height) + " " +
                                  pixelFormatName(view.format) + " frame, the stream expects " +
                                  std::to_string(width) + "x" + std::to_string(height) + " BGR8");
            break;
        }

        std::unique_lock lock(mutex_);
        int slot = oldest(SlotState::Free);
        if (slot < 0) {
            slot = oldest(SlotState::Queued);  // exists: only one slot is ever being decoded
            ++stats_.dropped;
        }
        slots_[slot].state = SlotState::Filling;
        if (captured > 0 && frame->sequence > nextSequence) stats_.missed += frame->sequence - nextSequence;
        lock.unlock();

        nextSequence = frame->sequence + 1;
        cv::Mat& image = slots_[slot].image;
        for (int y = 0; y < height; ++y) std::memcpy(image.ptr(y), view.row(y), static_cast<std::size_t>(width) * 3);

        lock.lock();
        slots_[slot].state = SlotState::Queued;
        slots_[slot].order = ++captured;
        stats_.captured = captured;
        lock.unlock();
        queued_.notify_one();
    }
    // No frame needs the light any more: off now, not after the ring is
    // drained (which the watchdog would take for a hung camera).
    watchdog_->disarm();
    (void)light_.set(false);
    {
        std::lock_guard lock(mutex_);
        captureDone_ = true;
        error_ = error;
    }
    queued_.notify_one();
}

void Streamer::recordTimings(const pipeline::StageTimings& timings)
{
    timings_[timingCount_++ % kTimingWindow] = timings;
}

pipeline::StageTimings Streamer::medianTimings()
{
    pipeline::StageTimings median;
    const std::size_t n = std::min<std::uint64_t>(timingCount_, kTimingWindow);
    if (n == 0) return median;
    for (const auto field : kStages) {
        for (std::size_t i = 0; i < n; ++i) medianScratch_[i] = timings_[i].*field;
        auto* middle = medianScratch_.data() + n / 2;
        std::nth_element(medianScratch_.data(), middle, medianScratch_.data() + n);
        median.*field = *middle;
    }
    return median;
}

void Streamer::printStats(const char* label, const StreamStats& s) const
{
    if (!options_.report) return;
    const pipeline::StageTimings& m = s.median;
    const std::uint64_t good = s.decoded - s.failed;
    // Formatted in pieces of few conversions into one buffer: libquadmath
    // (linked through OpenCV) registers printf extensions, which sends glibc's
    // printf down a path that mallocs for formats with many conversions, and
    // a progress line must not allocate. One write per line: the watchdog
    // thread writes to stderr too.
    char line[512];
    int n = std::snprintf(line, sizeof line, "%s: %.1f fps over %.1f s; %llu captured, %llu decoded (%llu failed), ",
                          label, s.fps(), s.seconds, static_cast<unsigned long long>(s.captured),
                          static_cast<unsigned long long>(s.decoded), static_cast<unsigned long long>(s.failed));
    n += std::snprintf(line + n, sizeof line - n, "%llu dropped, %llu missed; %.0f points/frame; decode busy %.0f%%; ",
                       static_cast<unsigned long long>(s.dropped), static_cast<unsigned long long>(s.missed),
                       good > 0 ? static_cast<double>(s.points) / static_cast<double>(good) : 0.0,
                       100.0 * s.decodeBusy);
    n += std::snprintf(line + n, sizeof line - n, "median ms: total %.2f = gradient %.2f + watershed %.2f + regions %.2f",
                       m.totalMs, m.gradientMs, m.watershedMs, m.regionsMs);
    std::snprintf(line + n, sizeof line - n, " + graph %.2f + edges %.2f + traversal %.2f + depth %.2f\n", m.graphMs,
                  m.edgesMs, m.decodeMs, m.depthMs);
    std::fputs(line, options_.report);
    std::fflush(options_.report);
}

StreamSummary Streamer::run()
{
    StreamSummary summary;
    {
        std::lock_guard lock(mutex_);
        for (Slot& slot : slots_) slot.state = SlotState::Free;
        captureDone_ = false;
        error_ = Status::ok();
        stats_ = StreamStats();
    }
    timingCount_ = 0;
    // Every way out of here leaves the LED off.
    struct LedOff {
        Streamer& streamer;
        ~LedOff()
        {
            (void)streamer.light_.set(false);
            streamer.watchdog_->disarm();
        }
    } ledOff{*this};
    if (!stop_.load()) {
        if (Status s = light_.set(true); !s) {
            summary.error = s.withContext("light: ");
            return summary;
        }
        ledOnNs_ = hal::monotonicNs();
        watchdog_->arm();
    }
    // A stop that came before or while the LED was switched on.
    if (stop_.load()) {
        summary.stopped = true;
        return summary;
    }

    const Clock::time_point start = Clock::now();
    Clock::time_point lastReport = start;
    double busySeconds = 0;
    std::thread capture([this] { captureLoop(); });

    std::unique_lock lock(mutex_);
    for (;;) {
        const int slot = oldest(SlotState::Queued);
        if (slot < 0) {
            if (captureDone_) break;
            // Bounded, so a stop from a signal handler (which cannot notify) is seen.
            queued_.wait_for(lock, std::chrono::milliseconds(50));
            continue;
        }
        slots_[slot].state = SlotState::Decoding;
        lock.unlock();

        const cv::Mat& image = slots_[slot].image;
        const FrameView view{image.data, image.cols, image.rows, static_cast<std::ptrdiff_t>(image.step),
                             PixelFormat::Bgr8};
        const Clock::time_point decodeStart = Clock::now();
        const auto result = decoder_.decode(view);
        busySeconds += secondsSince(decodeStart);
        if (result) {
            recordTimings(result->timings);
        } else if (options_.report && stats_.failed == 0) {
            std::fprintf(options_.report, "stream: decode failed (reported once): %s\n", result.message().c_str());
        }

        lock.lock();
        slots_[slot].state = SlotState::Free;
        if (result) {
            stats_.points += result->points.size();
        } else {
            ++stats_.failed;
        }
        ++stats_.decoded;
        if (options_.reportSeconds > 0 && secondsSince(lastReport) >= options_.reportSeconds) {
            lastReport = Clock::now();
            StreamStats snapshot = stats_;
            lock.unlock();
            snapshot.seconds = secondsSince(start);
            snapshot.decodeBusy = busySeconds / snapshot.seconds;
            snapshot.median = medianTimings();
            printStats("stream", snapshot);
            lock.lock();
        }
    }
    summary.stats = stats_;
    summary.error = error_;
    lock.unlock();
    capture.join();

    summary.stats.seconds = secondsSince(start);
    summary.stats.decodeBusy = summary.stats.seconds > 0 ? busySeconds / summary.stats.seconds : 0;
    summary.stats.median = medianTimings();
    summary.stopped = stop_.load();
    printStats("stream total", summary.stats);
    return summary;
}

}  // namespace stria::firmware
