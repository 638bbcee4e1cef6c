#pragma once
// The scan loop: wait for a press -> LED on -> settle -> capture -> LED off ->
// decode -> write results -> ready again. Everything that can be sized at
// start-up is (decoder workspace, depth map), so scan after scan runs in the
// same memory. The LED is off before decoding starts, after every error, on
// SIGINT/SIGTERM (requestStop) and after light.max_on_ms (LedWatchdog).
#include "firmware/app/devices.hpp"
#include "firmware/app/led_watchdog.hpp"
#include "firmware/formats/board_file.hpp"
#include "firmware/formats/scan_record.hpp"
#include "pipeline/decoder.hpp"

#include <atomic>
#include <memory>
#include <string>

namespace stria::firmware {

struct ScanOptions {
    std::string outDir;         // scan folders go here (created if missing)
    bool writeOutputs = true;   // false: decode and log only (soak tests)
    int maxScans = 0;           // run() returns after this many scans; 0 = until stopped
};

struct ScanResult {
    ScanRecord record;
    std::string folder;  // where the results are; empty if nothing was written
};

struct RunSummary {
    int scans = 0;
    int failed = 0;
    bool stopped = false;   // by requestStop() (a signal)
    Status buttonError;     // the button failed: the loop cannot go on
};

class Scanner {
public:
    // Loads pattern and calibration, creates the decoder, configures and
    // starts the camera, checks the output folder is writable. Every failure
    // is a message naming the file, key or device.
    static Result<std::unique_ptr<Scanner>> create(const BoardConfig& board, Devices devices, ScanOptions options);
    ~Scanner();

    // Waits for presses and scans until the button is interrupted (or its
    // simulated script ends), requestStop() or options.maxScans.
    RunSummary run();
    // One scan, as if the button had been pressed at pressNs (monotonic).
    ScanResult scanOnce(std::int64_t pressNs);

    // Async-signal-safe: LED off, end the loop, wake a waiting button.
    void requestStop();

    const Devices& devices() const { return devices_; }
    const pipeline::Decoder& decoder() const { return *decoder_; }

private:
    Scanner(const BoardConfig& board, Devices devices, ScanOptions options);
    Result<hal::CapturedFrame> captureLit(ScanRecord& record);
    Status decodeFrame(const hal::CapturedFrame& frame, ScanRecord& record);
    std::string writeResults(ScanRecord& record, bool withOutputs);

    BoardConfig board_;
    Devices devices_;
    ScanOptions options_;
    std::unique_ptr<pipeline::Decoder> decoder_;
    std::unique_ptr<LedWatchdog> watchdog_;
    pipeline::DecodeResult lastDecode_;
    cv::Mat depth_;  // CV_32FC1, camera size, allocated once
    std::uint64_t scanCount_ = 0;
    std::atomic<bool> stop_{false};
};

}  // namespace stria::firmware
