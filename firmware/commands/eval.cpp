// stria eval: the paper's noise and contrast study, graph decoder against the
// DP baseline, on the simulator (firmware/app/evaluation.hpp).
#include "firmware/app/evaluation.hpp"
#include "firmware/cli.hpp"
#include "firmware/formats/atomic_file.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

extern char** environ;

namespace stria::firmware {
namespace {

constexpr const char* kUsage = R"(usage:
  stria eval [--quick] [--scenes relief,...] [--albedo NAME] [--noise 0,2,4,8,16]
             [--contrast 1,0.7,0.5,0.3,0.2] [--seeds N] [--dp-passes N]
             [--dp-floor F] [--no-plots] [--plot-script PATH] --out DIR

For every scene x noise x contrast x seed, renders a frame with the simulated
desktop rig (camera 780x580, objects at 1000 mm), decodes it with the graph
decoder and with the DP baseline (Zhang et al. 2002), and scores both against
the ground truth: a point is an inlier when its error along its camera ray is
within 1% of the working distance (10 mm); ideal = the edge crossings a perfect
decoder would find.

  --quick        noise 2,8 and contrast 1,0.5 (unless given)
  --scenes       plane, sphere, relief, clutter, fan, fingertip, tube (default relief)
  --albedo       uniform, checker, coloured, photo (default: each scene's own,
                 as in stria render: relief photo, the others uniform)
  --noise        Gaussian noise sigmas in 8-bit digits
  --contrast     pattern contrasts in (0, 1]
  --seeds        scene and noise seeds 1..N (default 1)
  --dp-passes    passes of the multi-pass DP (default 3; 1 = plain DP)
  --dp-floor     the DP's candidate edge floor, intensity in (0, 1) (default 0.03)
  --no-plots     write the CSV only
  --plot-script  the plotting script (default: the source tree's
                 firmware/eval/plot_evaluation.py)

Writes DIR/evaluation.csv (atomically) and, with /usr/bin/python3 and
matplotlib, DIR/eval-error.png, DIR/eval-inliers.png and DIR/eval-time.png.)";

int run(std::span<const std::string> argv);
const Command kEval{"eval", "compare the graph decoder with the DP baseline on simulated scenes", kUsage, run};

// A comma-separated list of numbers; names the option and the bad item.
bool parseNumbers(const std::string& option, const std::string& text, std::vector<double>& out, std::string& error)
{
    out.clear();
    std::stringstream list(text);
    std::string item;
    while (std::getline(list, item, ',')) {
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0' || !std::isfinite(v)) {
            error = "option --" + option + " expects comma-separated numbers, not '" + item + "'";
            return false;
        }
        out.push_back(v);
    }
    if (out.empty()) error = "option --" + option + " needs at least one number";
    return !out.empty();
}

bool parseScenes(const std::string& text, std::vector<hal::sim::SceneKind>& out, std::string& error)
{
    out.clear();
    std::stringstream list(text);
    std::string item;
    while (std::getline(list, item, ',')) {
        const auto kind = hal::sim::sceneFromName(item);
        if (!kind) {
            error = "unknown scene '" + item + "' (plane, sphere, relief, clutter, fan, fingertip, tube)";
            return false;
        }
        out.push_back(*kind);
    }
    if (out.empty()) error = "option --scenes needs at least one scene";
    return !out.empty();
}

// On a terminal one line that updates in place; otherwise (logs, CI) a line
// at about every 10%, so a log shows progress without thousands of lines.
class ProgressBar {
public:
    ProgressBar() : terminal_(isatty(STDERR_FILENO) == 1), start_(std::chrono::steady_clock::now()) {}

    void update(int done, int total)
    {
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
        const int eta = static_cast<int>(elapsed / done * (total - done) + 0.5);
        const int percent = 100 * done / total;
        if (terminal_) {
            constexpr int kWidth = 30;
            const int filled = kWidth * done / total;
            std::fprintf(stderr, "\r[%s%s] %d/%d frames, ETA %d:%02d ", std::string(filled, '#').c_str(),
                         std::string(kWidth - filled, '.').c_str(), done, total, eta / 60, eta % 60);
            if (done == total) std::fputc('\n', stderr);
        } else if (percent / 10 > lastDecile_ || done == total) {
            lastDecile_ = percent / 10;
            std::fprintf(stderr, "eval: %d/%d frames (%d%%), ETA %d:%02d\n", done, total, percent, eta / 60, eta % 60);
        }
        std::fflush(stderr);
    }

private:
    bool terminal_;
    int lastDecile_ = 0;
    std::chrono::steady_clock::time_point start_;
};

// /usr/bin/python3 SCRIPT CSV DIR; the exit status, or -1 if it could not start.
int runPlotScript(const std::string& script, const std::string& csv, const std::string& dir)
{
    const std::string python = "/usr/bin/python3";
    std::vector<std::string> args{python, script, csv, dir};
    std::vector<char*> argvPtrs;
    for (std::string& a : args) argvPtrs.push_back(a.data());
    argvPtrs.push_back(nullptr);
    pid_t pid = 0;
    if (posix_spawn(&pid, python.c_str(), nullptr, nullptr, argvPtrs.data(), environ) != 0) return -1;
    int status = 0;
    if (waitpid(pid, &status, 0) != pid) return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

int run(std::span<const std::string> argv)
{
    Args args(argv, {"scenes", "albedo", "noise", "contrast", "seeds", "dp-passes", "dp-floor", "plot-script", "out"},
              {"quick", "no-plots"});
    if (!args.ok()) return usageError(kEval, args.error());
    if (!args.positional().empty()) return usageError(kEval, "unexpected argument '" + args.positional()[0] + "'");
    if (!args.require({"out"})) return usageError(kEval, args.error());

    EvaluationConfig config = args.has("quick") ? EvaluationConfig::quick() : EvaluationConfig{};
    std::string error;
    if (auto v = args.value("scenes"); v && !parseScenes(*v, config.scenes, error)) return usageError(kEval, error);
    if (auto v = args.value("noise"); v && !parseNumbers("noise", *v, config.noise, error))
        return usageError(kEval, error);
    if (auto v = args.value("contrast"); v && !parseNumbers("contrast", *v, config.contrast, error))
        return usageError(kEval, error);
    if (auto v = args.value("albedo")) {
        const auto albedo = hal::sim::albedoFromName(*v);
        if (!albedo) return usageError(kEval, "unknown albedo '" + *v + "' (uniform, checker, coloured, photo)");
        config.albedo = *albedo;
    }
    config.seeds = static_cast<int>(args.integer("seeds", 1));
    config.dp.passes = static_cast<int>(args.integer("dp-passes", config.dp.passes));
    config.dp.edgeFloor = args.number("dp-floor", config.dp.edgeFloor);
    if (!args.ok()) return usageError(kEval, args.error());
    if (Status s = config.validate(); !s) return usageError(kEval, s.message());

    const std::string dir = *args.value("out");
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return failure("eval", "cannot create output directory '" + dir + "': " + ec.message());

    ProgressBar bar;
    auto rows = runEvaluation(config, [&](int done, int total) { bar.update(done, total); });
    if (!rows) return failure("eval", rows.message());
    const std::string csvPath = (std::filesystem::path(dir) / "evaluation.csv").string();
    if (Status s = writeFileAtomically(csvPath, evaluationCsv(*rows)); !s) return failure("eval", s.message());
    std::printf("wrote %s (%zu frames)\n", csvPath.c_str(), rows->size());
    if (!rows->empty() && !rows->front().graph.available)
        std::printf("graph decoder unavailable (%s): its columns are empty\n",
                    rows->front().graph.unavailableReason.c_str());

    if (args.has("no-plots")) return kExitOk;
    const std::string script = args.valueOr("plot-script", STRIA_PLOT_SCRIPT);
    const int status = runPlotScript(script, csvPath, dir);
    if (status != 0)
        return failure("eval", "the CSV is written but the plots are not: '/usr/bin/python3 " + script + "' " +
                                   (status < 0 ? "could not be started" : "exited with " + std::to_string(status)) +
                                   ". It needs numpy and matplotlib (apt-get install python3-numpy "
                                   "python3-matplotlib); then run: /usr/bin/python3 " + script + " " + csvPath + " " +
                                   dir);
    std::printf("wrote %s/eval-error.png, eval-inliers.png, eval-time.png\n", dir.c_str());
    return kExitOk;
}

}  // namespace

STRIA_COMMAND(eval, kEval);

}  // namespace stria::firmware
