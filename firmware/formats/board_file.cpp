#include "firmware/formats/board_file.hpp"

#include "firmware/formats/file_storage.hpp"

#include <cmath>
#include <filesystem>
#include <initializer_list>

namespace stria::firmware {
namespace {

// Reads optional keys of one section; the first error is kept and names
// "section.key".
class Section {
public:
    Section(const cv::FileNode& node, std::string name) : node_(node), name_(std::move(name)) {}

    bool present() const { return !node_.empty() && !node_.isNone(); }

    void text(const char* key, std::string& out, bool required = false)
    {
        const cv::FileNode n = node_[key];
        if (missing(n, key, required)) return;
        if (!n.isString()) return fail(key, "must be a string");
        out = stripYamlComment(n.string());
    }
    void choice(const char* key, std::string& out, std::initializer_list<const char*> allowed, bool required = false)
    {
        text(key, out, required);
        if (!status_ || (out.empty() && !required)) return;
        std::string list;
        for (const char* a : allowed) {
            if (out == a) return;
            list += list.empty() ? a : std::string(", ") + a;
        }
        fail(key, "is '" + out + "', expected one of: " + list);
    }
    void integer(const char* key, int& out, int lo, int hi, bool required = false)
    {
        double v = out;
        number(key, v, lo, hi, required);
        if (!status_) return;
        if (v != std::floor(v)) return fail(key, "must be a whole number");
        out = static_cast<int>(v);
    }
    void number(const char* key, double& out, double lo, double hi, bool required = false)
    {
        const cv::FileNode n = node_[key];
        if (missing(n, key, required)) return;
        if (!n.isInt() && !n.isReal()) return fail(key, "must be a number");
        const double v = n.real();
        if (!(v >= lo && v <= hi))
            return fail(key, "is " + std::to_string(v) + ", must be between " + std::to_string(lo) + " and " +
                                 std::to_string(hi));
        out = v;
    }
    void flag(const char* key, bool& out)
    {
        const cv::FileNode n = node_[key];
        if (missing(n, key, false)) return;
        // FileStorage has no booleans: accept 0/1 and the YAML words.
        if (n.isInt() && (static_cast<int>(n) == 0 || static_cast<int>(n) == 1)) {
            out = static_cast<int>(n) == 1;
            return;
        }
        if (n.isString()) {
            const std::string s = stripYamlComment(n.string());
            if (s == "true" || s == "yes" || s == "on") return void(out = true);
            if (s == "false" || s == "no" || s == "off") return void(out = false);
        }
        fail(key, "must be true or false (or 1/0)");
    }
    void fail(const char* key, const std::string& what)
    {
        if (status_) status_ = Status::error("key '" + qualified(key) + "' " + what);
    }
    const Status& status() const { return status_; }

private:
    bool missing(const cv::FileNode& n, const char* key, bool required)
    {
        if (!status_) return true;
        if (!n.empty() && !n.isNone()) return false;
        if (required) fail(key, "is missing");
        return true;
    }
    std::string qualified(const char* key) const { return name_.empty() ? key : name_ + "." + key; }

    cv::FileNode node_;
    std::string name_;
    Status status_;
};

// The keys every GPIO-backed device shares (light, status LED, button).
void readGpioLine(Section& s, std::string& backend, std::string& chip, int& line, bool& activeLow)
{
    s.choice("backend", backend, {"sim", "gpiod"}, true);
    s.text("chip", chip);
    s.integer("line", line, 0, 4095);
    s.flag("active_low", activeLow);
    if (s.status() && backend == "gpiod" && (chip.empty() || line < 0)) s.fail("backend", "gpiod needs 'chip' and 'line'");
}

Status readLight(const cv::FileNode& node, const char* name, BoardLight& light)
{
    Section s(node, name);
    if (!s.present()) return Status::error(std::string("section '") + name + "' is missing");
    readGpioLine(s, light.backend, light.chip, light.line, light.activeLow);
    s.integer("max_on_ms", light.maxOnMs, 1, 60000);
    return s.status();
}

std::string resolve(const std::string& base, const std::string& path)
{
    if (path.empty() || std::filesystem::path(path).is_absolute()) return path;
    return (std::filesystem::path(base).parent_path() / path).lexically_normal().string();
}

}  // namespace

Result<BoardConfig> parseBoard(const std::string& text, const std::string& sourcePath)
{
    const std::string where = "board '" + sourcePath + "': ";
    cv::FileStorage fs;
    if (Status s = openFileStorage(fs, text, sourcePath); !s) return s.withContext("board: ");
    const cv::FileNode root = fs.root();
    BoardConfig board;
    board.path = sourcePath;

    Section top(root, "");
    top.text("name", board.name, true);
    std::string pattern, calibration, output;
    top.text("pattern", pattern, true);
    top.text("calibration", calibration, true);
    top.text("output_dir", output);
    top.integer("settle_ms", board.settleMs, 0, 10000);
    if (!top.status()) return top.status().withContext(where);

    Section camera(root["camera"], "camera");
    if (!camera.present()) return Status::error(where + "section 'camera' is missing");
    BoardCamera& cam = board.camera;
    camera.choice("backend", cam.backend, {"sim", "v4l2", "libcamera"}, true);
    camera.text("device", cam.device);
    camera.integer("width", cam.width, 1, 16384, true);
    camera.integer("height", cam.height, 1, 16384, true);
    camera.number("exposure_us", cam.exposureUs, 1, 10e6);
    camera.number("gain", cam.gain, 1, 64);
    camera.integer("buffers", cam.bufferCount, 1, 32);
    camera.integer("timeout_ms", cam.timeoutMs, 1, 60000);
    if (camera.status() && cam.backend == "v4l2" && cam.device.empty())
        camera.fail("device", "is missing (the V4L2 device node, e.g. /dev/video0)");
    if (!camera.status()) return camera.status().withContext(where);

    if (Status s = readLight(root["light"], "light", board.light); !s) return s.withContext(where);
    if (!root["status_led"].empty()) {
        board.statusLed.emplace();
        if (Status s = readLight(root["status_led"], "status_led", *board.statusLed); !s) return s.withContext(where);
    }

    Section button(root["button"], "button");
    if (!button.present()) return Status::error(where + "section 'button' is missing");
    BoardButton& btn = board.button;
    readGpioLine(button, btn.backend, btn.chip, btn.line, btn.activeLow);
    button.integer("debounce_ms", btn.debounceMs, 0, 1000);
    if (!button.status()) return button.status().withContext(where);

    Section decoder(root["decoder"], "decoder");
    pipeline::DecoderParams& p = board.decoder;
    decoder.number("t", p.t, 0, 1);
    decoder.number("alpha", p.alpha, 0, 100);
    decoder.number("A", p.A, 0, 100);
    decoder.number("beta", p.beta, 1e-6, 1e6);
    decoder.integer("token_bucket", p.tokenBucketSize, 0, 1000);
    decoder.number("token_error_limit", p.tokenErrorLimit, 0, 100);
    decoder.integer("min_component_regions", p.minComponentRegions, 0, 1000000);
    decoder.number("null_edge_ratio", p.nullEdgeRatio, 0, 1);
    decoder.integer("gradient_floor", p.gradientFloor, 0, 255);
    decoder.number("noise_floor_factor", p.noiseFloorFactor, 0, 10);
    decoder.flag("row_pairs", p.segmentRowPairs);
    decoder.integer("max_superpixels", p.maxSuperpixels, 0, 1 << 26);
    decoder.integer("max_graph_edges", p.maxGraphEdges, 0, 1 << 28);
    decoder.integer("max_points", p.maxPoints, 0, 1 << 28);
    if (!decoder.status()) return decoder.status().withContext(where);
    if (!root["decoder"]["crosstalk"].empty()) {
        const auto m = readMatrix(root["decoder"], "crosstalk", 3, 3);
        if (!m) return m.status().withContext(where + "decoder: ");
        for (int i = 0; i < 9; ++i) p.crosstalk.val[i] = static_cast<float>((*m)[i]);
    }

    const bool usesSim = cam.backend == "sim" || board.light.backend == "sim" || btn.backend == "sim";
    Section sim(root["sim"], "sim");
    if (usesSim) {
        BoardSim& s = board.sim;
        sim.choice("rig", s.rig, {"desktop", "desktop-large", "fingerprint", "endoscope"});
        sim.choice("scene", s.scene, {"plane", "sphere", "relief", "clutter", "fan", "fingertip", "tube"});
        sim.choice("albedo", s.albedo, {"uniform", "checker", "coloured", "photo"});
        int seed = static_cast<int>(s.seed);
        sim.integer("seed", seed, 0, 1 << 30);
        s.seed = static_cast<std::uint64_t>(seed);
        sim.number("noise", s.noise, 0, 255);
        sim.number("ambient", s.ambient, 0, 10);
        sim.number("contrast", s.contrast, 0.01, 1);
        sim.integer("samples_per_pixel", s.samplesPerPixel, 1, 64);
        sim.integer("frame_interval_us", s.frameIntervalUs, 100, 10000000);
        sim.flag("real_time", s.realTime);
        sim.text("presses", s.presses);
        if (!sim.status()) return sim.status().withContext(where);
    }

    board.patternPath = resolve(sourcePath, pattern);
    board.calibrationPath = resolve(sourcePath, calibration);
    board.outputDir = resolve(sourcePath, output);
    return board;
}

Result<BoardConfig> loadBoardFile(const std::string& path)
{
    const auto text = readTextFile(path);
    if (!text) return text.status().withContext("board: ");
    return parseBoard(*text, path);
}

}  // namespace stria::firmware
