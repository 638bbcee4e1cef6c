// stria scan: the scanner head's main loop.
#include "firmware/app/devices.hpp"
#include "firmware/app/log.hpp"
#include "firmware/app/scanner.hpp"
#include "firmware/app/stop_signals.hpp"
#include "firmware/cli.hpp"

#include <cstring>

namespace stria::firmware {
namespace {

constexpr const char* kUsage = R"(usage:
  stria scan --board BOARD.yaml [--out DIR] [--once] [--scans N] [--presses LIST] [--no-save]

Waits for a button press, then: LED on, settle, capture one frame, LED off,
decode, and write DIR/scan-<UTC time>-<seq>/ with points.ply, depth.tiff,
preview.png and scan.json (a failed scan writes scan.json with its error).
Ready for the next press after that. SIGINT/SIGTERM switch the LED off and
end the loop (exit 0).

  --board BOARD.yaml  the head: devices, pattern, calibration (see docs/boards.md)
  --out DIR           results folder (default: the board's output_dir)
  --once              one scan, then exit; the simulated button presses at once
  --scans N           exit after N scans
  --presses LIST      simulated button only: press times in ms, e.g. "100,900b,1500"
                      (b = the contact bounces); the loop ends after the last press
  --no-save           decode but write nothing (soak tests)

Exit status: 0 all scans succeeded (or stopped by a signal), 1 a start-up
error or a failed scan, 2 a wrong command line.)";

int run(std::span<const std::string> argv);
const Command kScan{"scan", "the scanner: wait for a press, light, capture, decode, store", kUsage, run};

int run(std::span<const std::string> argv)
{
    Args args(argv, {"board", "out", "scans", "presses"}, {"once", "no-save"});
    if (!args.ok()) return usageError(kScan, args.error());
    if (!args.positional().empty()) return usageError(kScan, "unexpected argument '" + args.positional()[0] + "'");
    if (!args.require({"board"})) return usageError(kScan, args.error());
    const long scans = args.integer("scans", 0);
    if (!args.ok()) return usageError(kScan, args.error());
    if (scans < 0) return usageError(kScan, "--scans must be 0 or more");

    auto board = loadBoardFile(*args.value("board"));
    if (!board) return failure("scan", board.message());
    std::optional<std::string> presses = args.value("presses");
    if (presses && board->button.backend != "sim")
        return usageError(kScan, "--presses needs the simulated button (button.backend: sim), this board has '" +
                                     board->button.backend + "'");
    const bool once = args.has("once");
    if (once && !presses && board->button.backend == "sim") presses = "0";

    ScanOptions options;
    options.outDir = args.valueOr("out", board->outputDir);
    options.writeOutputs = !args.has("no-save");
    options.maxScans = once ? 1 : static_cast<int>(scans);
    if (options.writeOutputs && options.outDir.empty())
        return usageError(kScan, "no results folder: give --out or set output_dir in '" + board->path + "'");

    auto devices = openDevices(*board, presses);
    if (!devices) return failure("scan", devices.message());
    auto scanner = Scanner::create(*board, std::move(*devices), options);
    if (!scanner) return failure("scan", scanner.message());

    const StopSignals signals(**scanner);
    const RunSummary summary = (*scanner)->run();
    if (summary.stopped) {
        logInfo("stria: stopped by %s after %d scans (%d failed); LED off", strsignal(StopSignals::received()),
                summary.scans, summary.failed);
        return kExitOk;
    }
    logInfo("stria: %d scans, %d failed%s%s", summary.scans, summary.failed,
            options.writeOutputs ? "; results in " : "", options.writeOutputs ? options.outDir.c_str() : "");
    if (!summary.buttonError) return kExitFailure;
    if (once && summary.scans == 0) {
        logError("stria: --once ended without a press");
        return kExitFailure;
    }
    return summary.failed == 0 ? kExitOk : kExitFailure;
}

}  // namespace

STRIA_COMMAND(scan, kScan);

}  // namespace stria::firmware
