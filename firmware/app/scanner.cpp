#include "firmware/app/scanner.hpp"

#include "firmware/app/log.hpp"
#include "firmware/formats/atomic_file.hpp"
#include "firmware/formats/calibration_file.hpp"
#include "firmware/formats/image_file.hpp"
#include "firmware/formats/pattern_file.hpp"
#include "firmware/formats/ply_file.hpp"
#include "firmware/formats/preview.hpp"
#include "hal/clock.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <exception>
#include <cstdio>
#include <ctime>
#include <filesystem>

namespace stria::firmware {
namespace {

namespace fs = std::filesystem;

// A camera may hand out frames that were already exposing when the LED came
// on (queued buffers, a free-running sensor); these are dropped.
constexpr int kMaxStaleFrames = 4;

double msBetween(std::int64_t fromNs, std::int64_t toNs) { return static_cast<double>(toNs - fromNs) / 1e6; }

// "2026-11-23T21:30:05.123Z" (record) and "20261123T213005.123Z" (folder names).
std::string utcNow(bool compact)
{
    const auto now = std::chrono::system_clock::now();
    const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
    const int ms = static_cast<int>(
        std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000);
    std::tm tm{};
    gmtime_r(&seconds, &tm);
    char buffer[40];
    std::strftime(buffer, sizeof buffer, compact ? "%Y%m%dT%H%M%S" : "%Y-%m-%dT%H:%M:%S", &tm);
    return std::string(buffer) + "." + (ms < 100 ? (ms < 10 ? "00" : "0") : "") + std::to_string(ms) + "Z";
}

Status syncDirectory(const std::string& path)
{
    const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return Status::error("cannot open folder '" + path + "': " + std::strerror(errno));
    const int rc = fsync(fd);
    const int err = errno;
    close(fd);
    if (rc != 0) return Status::error("cannot sync folder '" + path + "': " + std::strerror(err));
    return Status::ok();
}

}  // namespace

Scanner::Scanner(const BoardConfig& board, Devices devices, ScanOptions options) :
    board_(board), devices_(std::move(devices)), options_(std::move(options))
{
}

Scanner::~Scanner()
{
    watchdog_.reset();
    if (devices_.light) (void)devices_.light->set(false);
    if (devices_.statusLed) (void)devices_.statusLed->set(false);
    if (devices_.camera) devices_.camera->stop();
}

Result<std::unique_ptr<Scanner>> Scanner::create(const BoardConfig& board, Devices devices, ScanOptions options)
{
    const std::string where = "board '" + board.path + "': ";
    std::unique_ptr<Scanner> scanner(new Scanner(board, std::move(devices), std::move(options)));
    Scanner& s = *scanner;
    // The LED starts off whatever state the line was left in.
    if (Status st = s.devices_.light->set(false); !st) return st.withContext("light: ");

    const auto pattern = loadPatternFile(board.patternPath);
    if (!pattern) return pattern.status().withContext(where);
    const auto rig = loadCalibrationFile(board.calibrationPath);
    if (!rig) return rig.status().withContext(where);
    if (rig->camera().width != board.camera.width || rig->camera().height != board.camera.height)
        return Status::error(where + "camera is " + std::to_string(board.camera.width) + "x" +
                             std::to_string(board.camera.height) + " but calibration '" + board.calibrationPath +
                             "' is for " + std::to_string(rig->camera().width) + "x" +
                             std::to_string(rig->camera().height));
    const double exposeMs = board.settleMs + board.camera.exposureUs / 1000.0;
    if (exposeMs >= board.light.maxOnMs)
        return Status::error(where + "settle_ms + camera.exposure_us (" + std::to_string(exposeMs) +
                             " ms) do not fit in light.max_on_ms (" + std::to_string(board.light.maxOnMs) + " ms)");
    auto decoder = pipeline::Decoder::create(*pattern, *rig, board.decoder);
    if (!decoder) return decoder.status().withContext("decoder: ");
    s.decoder_ = std::move(*decoder);
    s.depth_.create(board.camera.height, board.camera.width, CV_32FC1);

    if (s.options_.writeOutputs) {
        std::error_code ec;
        fs::create_directories(s.options_.outDir, ec);
        if (ec) return Status::error("output folder '" + s.options_.outDir + "' cannot be created: " + ec.message());
        // Prove now, not at the first press, that results can be stored.
        if (Status st = writeFileAtomically(s.options_.outDir + "/.stria-write-test", std::string("ok\n")); !st)
            return Status::error("output folder '" + s.options_.outDir + "' is not writable: " + st.message());
        fs::remove(s.options_.outDir + "/.stria-write-test", ec);
    }

    hal::Camera& camera = *s.devices_.camera;
    hal::CameraConfig config;
    config.width = board.camera.width;
    config.height = board.camera.height;
    config.exposureUs = board.camera.exposureUs;
    config.analogueGain = board.camera.gain;
    config.bufferCount = board.camera.bufferCount;
    if (Status st = camera.configure(config); !st) return st;
    for (const std::string& control : camera.missingControls())
        logWarning("stria: camera %s has no '%s' control: the scan runs with the camera's own setting",
                   camera.backendName(), control.c_str());
    if (Status st = camera.start(); !st) return st;
    s.watchdog_ = std::make_unique<LedWatchdog>(*s.devices_.light, std::chrono::milliseconds(board.light.maxOnMs));

    logInfo("stria: board '%s' ready: camera %s %dx%d, exposure %.0f us, gain %.2f, settle %d ms; decoder workspace "
            "%.1f MB%s; results in %s",
            board.name.c_str(), camera.backendName(), config.width, config.height, config.exposureUs,
            config.analogueGain, board.settleMs, static_cast<double>(s.decoder_->workspaceBytes()) / 1e6,
            s.decoder_->workspaceHugePagesAdvised() ? " (huge pages)" : " (4 KB pages)",
            s.options_.writeOutputs ? s.options_.outDir.c_str() : "(not saved)");
    return scanner;
}

void Scanner::requestStop()
{
    stop_.store(true);
    (void)devices_.light->set(false);
    devices_.button->interrupt();
}

RunSummary Scanner::run()
{
    RunSummary summary;
    while (!stop_.load() && (options_.maxScans == 0 || summary.scans < options_.maxScans)) {
        if (devices_.statusLed) (void)devices_.statusLed->set(true);
        // A bounded wait, so a stop that raced the wait is seen within a second.
        const auto wait = devices_.button->waitForPress(std::chrono::seconds(1));
        if (devices_.statusLed) (void)devices_.statusLed->set(false);
        if (!wait) {
            logError("button: %s", wait.message().c_str());
            summary.buttonError = wait.status();
            break;
        }
        if (*wait == hal::ButtonWait::TimedOut) continue;
        if (*wait == hal::ButtonWait::Interrupted) break;
        const ScanResult result = scanOnce(hal::monotonicNs());
        ++summary.scans;
        if (!result.record.ok) ++summary.failed;
    }
    summary.stopped = stop_.load();
    return summary;
}

Result<hal::CapturedFrame> Scanner::captureLit(ScanRecord& record)
{
    hal::Light& light = *devices_.light;
    // Whatever happens below (an error, an exception from a library), the LED
    // goes off when this function is left.
    struct LedOff {
        Scanner& scanner;
        ScanRecord& record;
        ~LedOff()
        {
            (void)scanner.devices_.light->set(false);
            scanner.watchdog_->disarm();
            record.ledOffNs = hal::monotonicNs();
        }
    } ledOff{*this, record};

    if (stop_.load()) return Status::error("stopped before the LED was switched on");
    if (Status s = light.set(true); !s) return s.withContext("light: ");
    record.ledOnNs = hal::monotonicNs();
    watchdog_->arm();
    // A stop that arrived while the LED was being switched on.
    if (stop_.load()) return Status::error("stopped while the LED was on");

    hal::sleepUntilNs(record.ledOnNs + std::int64_t{board_.settleMs} * 1000000);
    record.captureNs = hal::monotonicNs();
    const std::chrono::milliseconds timeout(board_.camera.timeoutMs);
    for (int stale = 0;; ++stale) {
        auto frame = devices_.camera->capture(timeout);
        if (!frame) return frame.status();
        if (frame->timestampNs >= record.ledOnNs) {
            if (watchdog_->fired())
                return Status::error("the LED was forced off after light.max_on_ms = " +
                                     std::to_string(board_.light.maxOnMs) + " ms, before the frame was complete");
            if (stop_.load()) return Status::error("stopped during the exposure");
            return frame;
        }
        if (stale == kMaxStaleFrames)
            return Status::error(std::string("camera '") + devices_.camera->backendName() + "': " +
                                 std::to_string(kMaxStaleFrames + 1) +
                                 " frames in a row started exposing before the LED was on (check the frame timestamps)");
    }
}

Status Scanner::decodeFrame(const hal::CapturedFrame& frame, ScanRecord& record)
{
    record.frameSequence = frame.sequence;
    record.exposureStartNs = frame.timestampNs;
    record.exposureUs = frame.exposureUs;
    record.gain = frame.analogueGain;
    record.decodeStartNs = hal::monotonicNs();
    auto result = decoder_->decode(frame.view);
    if (!result) return result.status().withContext("decoder: ");
    lastDecode_ = *result;
    record.segmentation = decoder_->params().segmentRowPairs ? "row_pairs" : "rows";
    record.points = static_cast<int>(result->points.size());
    record.superpixels = result->superpixels;
    record.graphEdges = result->graphEdges;
    record.decodedRegions = result->decodedRegions;
    record.truncated = result->truncated;
    record.decode = result->timings;
    return Status::ok();
}

ScanResult Scanner::scanOnce(std::int64_t pressNs)
{
    ScanResult out;
    ScanRecord& record = out.record;
    record.scan = ++scanCount_;
    record.board = board_.name;
    record.timeUtc = utcNow(false);
    record.cameraBackend = devices_.camera->backendName();
    record.pressNs = pressNs;

    auto frame = captureLit(record);
    record.captureMs = msBetween(record.ledOnNs ? record.ledOnNs : pressNs, record.ledOffNs);
    // Our code reports errors as Status; OpenCV and the C++ library may still
    // throw (bad_alloc, cv::Exception). A daemon turns that into a failed scan.
    Status status;
    try {
        status = frame ? decodeFrame(*frame, record) : frame.status();
    } catch (const std::exception& e) {
        status = Status::error(std::string("decoding threw: ") + e.what());
    }
    record.ok = status.isOk();
    record.error = status.message();
    record.totalMs = msBetween(pressNs, hal::monotonicNs());
    if (options_.writeOutputs) {
        try {
            out.folder = writeResults(record, record.ok);
        } catch (const std::exception& e) {
            record.ok = false;
            record.error += (record.error.empty() ? "" : "; ") + std::string("writing results threw: ") + e.what();
        }
    }

    if (record.ok) {
        logInfo("scan %llu: %d points%s, decode %.1f ms, total %.1f ms%s%s",
                static_cast<unsigned long long>(record.scan), record.points,
                record.truncated ? " (truncated: a decoder capacity was reached)" : "", record.decode.totalMs,
                record.totalMs, out.folder.empty() ? "" : "; results in ", out.folder.c_str());
    } else {
        logError("scan %llu failed: %s%s%s", static_cast<unsigned long long>(record.scan), record.error.c_str(),
                 out.folder.empty() ? "" : "; record in ", out.folder.c_str());
    }
    return out;
}

std::string Scanner::writeResults(ScanRecord& record, bool withOutputs)
{
    const std::int64_t writeStartNs = hal::monotonicNs();
    char seq[16];
    std::snprintf(seq, sizeof seq, "%04llu", static_cast<unsigned long long>(record.scan));
    const std::string name = "scan-" + utcNow(true) + "-" + seq;
    const std::string folder = options_.outDir + "/" + name;
    // Everything goes into a hidden folder that is renamed when complete, so
    // a reader never sees a scan folder with some of its files missing.
    const std::string staging = options_.outDir + "/." + name + ".tmp";
    std::error_code ec;
    const auto nothingSaved = [&](const Status& why) {
        fs::remove_all(staging, ec);
        record.ok = false;
        record.error += (record.error.empty() ? "" : "; ") + ("nothing saved: " + why.message());
        return std::string();
    };
    if (!fs::create_directory(staging, ec) || ec)
        return nothingSaved(Status::error("cannot create '" + staging + "': " + (ec ? ec.message() : "it exists")));

    Status status;
    const auto write = [&](const std::string& file, auto&& writer) {
        if (!status) return;
        status = writer(staging + "/" + file);
        if (status) record.files.push_back(file);
    };
    if (withOutputs) {
        write("points.ply", [&](const std::string& p) { return writePly(p, lastDecode_.points); });
        decoder_->fillDepthMap(depth_);
        write("depth.tiff", [&](const std::string& p) { return writeTiffFloat(p, depth_); });
        write("preview.png", [&](const std::string& p) { return writePng(p, depthPreview(depth_)); });
        if (!status) {
            // The scan itself worked; the record says why its results are missing.
            record.ok = false;
            record.error = "results not saved: " + status.message();
            record.files.clear();
            status = Status::ok();
            for (const auto& entry : fs::directory_iterator(staging, ec)) fs::remove(entry.path(), ec);
        }
    }
    // The record's own write is the one thing these times leave out.
    const std::int64_t nowNs = hal::monotonicNs();
    record.writeMs = msBetween(writeStartNs, nowNs);
    record.totalMs = msBetween(record.pressNs, nowNs);
    status = writeScanRecord(staging + "/scan.json", record);
    if (status) {
        fs::rename(staging, folder, ec);
        if (ec) status = Status::error("cannot rename '" + staging + "' to '" + folder + "': " + ec.message());
    }
    if (status) status = syncDirectory(options_.outDir);
    if (!status) return nothingSaved(status);
    return folder;
}

}  // namespace stria::firmware
