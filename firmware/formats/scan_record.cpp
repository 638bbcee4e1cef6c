#include "firmware/formats/scan_record.hpp"

#include "firmware/formats/atomic_file.hpp"
#include "firmware/formats/file_storage.hpp"

#include <cstdio>

namespace stria::firmware {
namespace {

std::string quoted(const std::string& s)
{
    std::string out = "\"";
    for (const char c : s) {
        if (c == '"' || c == '\\') {
            out += '\\';
            out += c;
        } else if (static_cast<unsigned char>(c) < 0x20) {
            char buffer[8];
            std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
            out += buffer;
        } else {
            out += c;
        }
    }
    return out + "\"";
}

std::string number(double v)
{
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.3f", v);
    return buffer;
}

// FileStorage reads JSON integers as 32-bit ints, so 64-bit times are
// written as decimal strings.
std::string bigInteger(std::int64_t v) { return quoted(std::to_string(v)); }

}  // namespace

std::string scanRecordJson(const ScanRecord& r)
{
    const auto& t = r.decode;
    std::string files;
    for (const auto& f : r.files) files += (files.empty() ? "" : ", ") + quoted(f);
    std::string json = "{\n";
    json += "  \"time\": " + quoted(r.timeUtc) + ",\n";
    json += "  \"board\": " + quoted(r.board) + ",\n";
    json += "  \"scan\": " + std::to_string(r.scan) + ",\n";
    json += "  \"status\": " + quoted(r.ok ? "ok" : "failed") + ",\n";
    json += "  \"error\": " + quoted(r.error) + ",\n";
    json += "  \"camera\": {\"backend\": " + quoted(r.cameraBackend) + ", \"frame\": " + bigInteger(static_cast<std::int64_t>(r.frameSequence)) +
            ", \"exposure_us\": " + number(r.exposureUs) + ", \"gain\": " + number(r.gain) + "},\n";
    json += "  \"monotonic_ns\": {\"press\": " + bigInteger(r.pressNs) + ", \"led_on\": " + bigInteger(r.ledOnNs) +
            ", \"capture\": " + bigInteger(r.captureNs) + ", \"exposure_start\": " + bigInteger(r.exposureStartNs) +
            ", \"led_off\": " + bigInteger(r.ledOffNs) + ", \"decode_start\": " + bigInteger(r.decodeStartNs) + "},\n";
    json += "  \"segmentation\": " + quoted(r.segmentation) + ",\n";
    json += "  \"counts\": {\"points\": " + std::to_string(r.points) + ", \"superpixels\": " + std::to_string(r.superpixels) +
            ", \"graph_edges\": " + std::to_string(r.graphEdges) + ", \"decoded_regions\": " +
            std::to_string(r.decodedRegions) + ", \"truncated\": " + std::to_string(r.truncated ? 1 : 0) + "},\n";
    json += "  \"timings_ms\": {\"capture\": " + number(r.captureMs) + ", \"gradient\": " + number(t.gradientMs) +
            ", \"watershed\": " + number(t.watershedMs) + ", \"regions\": " + number(t.regionsMs) +
            ", \"graph\": " + number(t.graphMs) + ", \"edges\": " + number(t.edgesMs) + ", \"decode\": " +
            number(t.decodeMs) + ", \"depth\": " + number(t.depthMs) + ", \"decoder_total\": " + number(t.totalMs) +
            ", \"write\": " + number(r.writeMs) + ", \"total\": " + number(r.totalMs) + "},\n";
    json += "  \"files\": [" + files + "]\n}\n";
    return json;
}

Status writeScanRecord(const std::string& path, const ScanRecord& record)
{
    return writeFileAtomically(path, scanRecordJson(record));
}

Result<ScanRecord> readScanRecord(const std::string& path)
{
    const auto text = readTextFile(path);
    if (!text) return text.status().withContext("scan record: ");
    cv::FileStorage fs;
    if (Status s = openFileStorage(fs, *text, path); !s) return s.withContext("scan record: ");
    const std::string where = "scan record '" + path + "': ";
    const cv::FileNode root = fs.root();
    ScanRecord r;
    auto str = [&](const cv::FileNode& n, const char* key, std::string& out) {
        auto v = readString(n, key);
        if (v) out = *v;
        return v ? Status::ok() : v.status();
    };
    auto big = [&](const cv::FileNode& n, const char* key, std::int64_t& out) {
        std::string s;
        if (Status st = str(n, key, s); !st) return st;
        try {
            out = std::stoll(s);
        } catch (...) {
            return Status::error(std::string("key '") + key + "' is not an integer: '" + s + "'");
        }
        return Status::ok();
    };
    auto integer = [&](const cv::FileNode& n, const char* key, int& out) {
        auto v = readInt(n, key);
        if (v) out = *v;
        return v ? Status::ok() : v.status();
    };
    std::string status;
    std::int64_t frame = 0;
    int scan = 0, truncated = 0;
    const cv::FileNode camera = root["camera"], times = root["monotonic_ns"], counts = root["counts"];
    for (Status s : {str(root, "time", r.timeUtc), str(root, "board", r.board), integer(root, "scan", scan),
                     str(root, "status", status), str(root, "error", r.error),
                     str(camera, "backend", r.cameraBackend), big(camera, "frame", frame),
                     big(times, "press", r.pressNs), big(times, "led_on", r.ledOnNs), big(times, "capture", r.captureNs),
                     big(times, "exposure_start", r.exposureStartNs), big(times, "led_off", r.ledOffNs),
                     big(times, "decode_start", r.decodeStartNs), integer(counts, "points", r.points),
                     integer(counts, "superpixels", r.superpixels), integer(counts, "graph_edges", r.graphEdges),
                     integer(counts, "decoded_regions", r.decodedRegions), integer(counts, "truncated", truncated)}) {
        if (!s) return s.withContext(where);
    }
    // Records written before the key existed were all decoded on the camera's rows.
    if (!root["segmentation"].empty())
        if (Status s = str(root, "segmentation", r.segmentation); !s) return s.withContext(where);
    r.scan = static_cast<std::uint64_t>(scan);
    r.frameSequence = static_cast<std::uint64_t>(frame);
    r.ok = status == "ok";
    r.truncated = truncated != 0;
    r.exposureUs = camera["exposure_us"].real();
    r.gain = camera["gain"].real();
    const cv::FileNode t = root["timings_ms"];
    r.captureMs = t["capture"].real();
    r.decode.totalMs = t["decoder_total"].real();
    r.writeMs = t["write"].real();
    r.totalMs = t["total"].real();
    for (const auto& f : root["files"]) r.files.push_back(f.string());
    return r;
}

}  // namespace stria::firmware
