// stria stream: video mode, continuous capture and decode with the LED on.
#include "firmware/app/devices.hpp"
#include "firmware/app/log.hpp"
#include "firmware/app/stop_signals.hpp"
#include "firmware/app/stream.hpp"
#include "firmware/cli.hpp"
#include "firmware/formats/calibration_file.hpp"
#include "firmware/formats/image_file.hpp"
#include "firmware/formats/pattern_file.hpp"
#include "hal/sim/replay_camera.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

namespace stria::firmware {
namespace {

constexpr const char* kUsage = R"(usage:
  stria stream --board BOARD.yaml [--frames N] [--seconds S] [--replay DIR_OR_COUNT]
               [--fps F] [--slots N] [--report-every S]

Video mode: the LED stays on while the camera captures continuously and a
second thread decodes. Frames wait in a ring of --slots frame buffers (3);
when the decoder falls behind, the oldest waiting frame is dropped for the
newest. Every --report-every seconds (1; 0 = never) a line on stderr gives
the decoded frames per second, the captured, decoded, dropped and missed
(never collected from the sensor) frames and the median time of each decoder
stage; the same line ends the stream. The LED goes off at the end, on an
error and on SIGINT/SIGTERM (exit 0).

  --board BOARD.yaml    the head: devices, pattern, calibration (see docs/boards.md)
  --frames N            stop after N captured frames (default: no limit)
  --seconds S           stop after S seconds (default: no limit)
  --replay COUNT        instead of the board's camera, replay COUNT frames of the
                        board's simulated scene (rendered at start-up, each with
                        its own noise) in a loop; needs a board with a sim backend
  --replay DIR          replay the .png frames of DIR (sorted by name) in a loop
  --fps F               replay rate (default: the board's sim.frame_interval_us)
  --slots N             frame buffers in the ring (>= 2, default 3)
  --report-every S      progress line period in seconds (default 1; 0 = none)

Exit status: 0 the stream ended by a limit or a signal, 1 a start-up,
camera or LED error, 2 a wrong command line.)";

int run(std::span<const std::string> argv);
const Command kStream{"stream", "video mode: continuous capture and decode with the LED on", kUsage, run};

// The .png files of `dir`, sorted by name, as BGR frames.
Result<std::vector<cv::Mat>> readFrameFolder(const std::string& dir)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    std::vector<std::string> paths;
    for (const auto& entry : fs::directory_iterator(dir, ec))
        if (entry.is_regular_file() && entry.path().extension() == ".png") paths.push_back(entry.path().string());
    if (ec) return Status::error("replay folder '" + dir + "': " + ec.message());
    if (paths.empty()) return Status::error("replay folder '" + dir + "' has no .png frames");
    std::sort(paths.begin(), paths.end());
    std::vector<cv::Mat> frames;
    for (const std::string& path : paths) {
        auto image = readPng(path);
        if (!image) return image.status();
        frames.push_back(std::move(*image));
    }
    return frames;
}

// The frames --replay asks for: a count of simulator frames or a folder.
Result<std::vector<cv::Mat>> replayFrames(const std::string& replay, const BoardConfig& board, const Devices& devices)
{
    const bool isCount = !replay.empty() && std::all_of(replay.begin(), replay.end(), [](char c) {
        return c >= '0' && c <= '9';
    });
    if (!isCount) {
        if (!std::filesystem::is_directory(replay))
            return Status::error("--replay '" + replay + "' is neither a frame count nor a folder");
        return readFrameFolder(replay);
    }
    if (!devices.world)
        return Status::error("--replay " + replay + " renders the simulated scene, but board '" + board.path +
                             "' has no sim backend: give a folder of .png frames instead");
    const long count = std::strtol(replay.c_str(), nullptr, 10);
    if (count < 1 || count > 1000) return Status::error("--replay " + replay + ": the frame count must be 1..1000");
    return hal::sim::renderReplayFrames(*devices.world, static_cast<int>(count), board.camera.exposureUs,
                                        board.camera.gain);
}

int run(std::span<const std::string> argv)
{
    Args args(argv, {"board", "frames", "seconds", "replay", "fps", "slots", "report-every"}, {});
    if (!args.ok()) return usageError(kStream, args.error());
    if (!args.positional().empty()) return usageError(kStream, "unexpected argument '" + args.positional()[0] + "'");
    if (!args.require({"board"})) return usageError(kStream, args.error());
    StreamOptions options;
    const long frames = args.integer("frames", 0);
    options.maxSeconds = args.number("seconds", 0);
    const double fps = args.number("fps", 0);
    options.slots = static_cast<int>(args.integer("slots", options.slots));
    options.reportSeconds = args.number("report-every", options.reportSeconds);
    if (!args.ok()) return usageError(kStream, args.error());
    if (frames < 0) return usageError(kStream, "--frames must be 0 or more");
    if (!(options.maxSeconds >= 0) || !std::isfinite(options.maxSeconds))
        return usageError(kStream, "--seconds must be 0 or more");
    if (args.has("fps") && !(fps > 0 && fps <= 10000)) return usageError(kStream, "--fps must be in (0, 10000]");
    if (args.has("fps") && !args.has("replay")) return usageError(kStream, "--fps sets the rate of --replay only");
    if (options.slots < 2 || options.slots > 64) return usageError(kStream, "--slots must be 2..64");
    if (!(options.reportSeconds >= 0)) return usageError(kStream, "--report-every must be 0 or more");
    options.maxFrames = static_cast<std::uint64_t>(frames);

    auto board = loadBoardFile(*args.value("board"));
    if (!board) return failure("stream", board.message());
    const std::string where = "board '" + board->path + "': ";
    auto devices = openDevices(*board);
    if (!devices) return failure("stream", devices.message());
    const auto pattern = loadPatternFile(board->patternPath);
    if (!pattern) return failure("stream", where + pattern.message());
    const auto rig = loadCalibrationFile(board->calibrationPath);
    if (!rig) return failure("stream", where + rig.message());
    if (rig->camera().width != board->camera.width || rig->camera().height != board->camera.height)
        return failure("stream", where + "camera is " + std::to_string(board->camera.width) + "x" +
                                     std::to_string(board->camera.height) + " but calibration '" +
                                     board->calibrationPath + "' is for " + std::to_string(rig->camera().width) +
                                     "x" + std::to_string(rig->camera().height));
    auto decoder = pipeline::Decoder::create(*pattern, *rig, board->decoder);
    if (!decoder) return failure("stream", "decoder: " + decoder.message());

    hal::Camera* camera = devices->camera.get();
    std::unique_ptr<hal::sim::ReplayCamera> replay;
    std::int64_t frameIntervalNs = board->camera.backend == "sim" ? std::int64_t{board->sim.frameIntervalUs} * 1000 : 0;
    if (const auto replayArg = args.value("replay")) {
        auto replayed = replayFrames(*replayArg, *board, *devices);
        if (!replayed) return failure("stream", replayed.message());
        frameIntervalNs = args.has("fps") ? std::llround(1e9 / fps) : std::int64_t{board->sim.frameIntervalUs} * 1000;
        auto created = hal::sim::ReplayCamera::create(std::move(*replayed), frameIntervalNs);
        if (!created) return failure("stream", created.message());
        replay = std::move(*created);
        camera = replay.get();
    }
    // Each frame re-arms the LED watchdog: frames must come faster than it fires.
    options.ledMaxGap = std::chrono::milliseconds(board->light.maxOnMs);
    options.captureTimeout = std::chrono::milliseconds(board->camera.timeoutMs);
    if (frameIntervalNs >= std::int64_t{board->light.maxOnMs} * 1000000)
        return failure("stream", where + "a frame every " + std::to_string(frameIntervalNs / 1000000) +
                                     " ms cannot keep the LED on: light.max_on_ms is " +
                                     std::to_string(board->light.maxOnMs) + " ms");

    hal::CameraConfig config;
    config.width = board->camera.width;
    config.height = board->camera.height;
    config.exposureUs = board->camera.exposureUs;
    config.analogueGain = board->camera.gain;
    config.bufferCount = board->camera.bufferCount;
    auto streamer = Streamer::create(*camera, *devices->light, **decoder, config, options);
    if (!streamer) return failure("stream", streamer.message());
    const std::string replayed = replay ? ", " + std::to_string(replay->frameCount()) + " frames replayed" : "";
    logInfo("stria: board '%s' streaming: camera %s %dx%d%s, %d frame slots; decoder workspace %.1f MB%s",
            board->name.c_str(), camera->backendName(), config.width, config.height, replayed.c_str(), options.slots,
            static_cast<double>((*decoder)->workspaceBytes()) / 1e6,
            (*decoder)->workspaceHugePagesAdvised() ? " (huge pages)" : " (4 KB pages)");

    const StopSignals signals(**streamer);
    const StreamSummary summary = (*streamer)->run();
    if (!summary.error) return failure("stream", summary.error.message() + " (LED off)");
    if (summary.stopped) logInfo("stria: stopped by %s; LED off", strsignal(StopSignals::received()));
    return kExitOk;
}

}  // namespace

STRIA_COMMAND(stream, kStream);

}  // namespace stria::firmware
