#pragma once
// The small JSON record written beside every scan (and alone for a failed
// scan): when, which board, what came out, how long each stage took, the
// exposure actually applied and when the LED was on. Times named *Ns are
// CLOCK_MONOTONIC nanoseconds, comparable with frame timestamps and LED logs.
#include "pipeline/decoder.hpp"
#include "pipeline/status.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace stria::firmware {

struct ScanRecord {
    std::string timeUtc;         // ISO 8601, e.g. 2026-11-23T21:30:05.123Z
    std::string board;           // board name
    std::uint64_t scan = 0;      // 1, 2, ... since start-up
    bool ok = false;
    std::string error;           // why the scan failed (empty when ok)

    std::string cameraBackend;
    std::uint64_t frameSequence = 0;
    double exposureUs = 0, gain = 0;  // as applied by the camera

    std::int64_t pressNs = 0;          // debounced press seen
    std::int64_t ledOnNs = 0;          // LED switched on
    std::int64_t captureNs = 0;        // capture requested (ledOnNs + settle)
    std::int64_t exposureStartNs = 0;  // frame timestamp
    std::int64_t ledOffNs = 0;         // LED switched off
    std::int64_t decodeStartNs = 0;

    std::string segmentation = "rows";  // the decoder's mode: "rows", or "row_pairs" (DecoderParams::segmentRowPairs)
    int points = 0, superpixels = 0, graphEdges = 0, decodedRegions = 0;
    bool truncated = false;
    pipeline::StageTimings decode;
    double captureMs = 0, writeMs = 0, totalMs = 0;  // press -> record written

    std::vector<std::string> files;  // result files beside this record (not the record itself)
};

std::string scanRecordJson(const ScanRecord& record);
Status writeScanRecord(const std::string& path, const ScanRecord& record);
// Reads what writeScanRecord writes (tests and tools); errors name file and key.
Result<ScanRecord> readScanRecord(const std::string& path);

}  // namespace stria::firmware
