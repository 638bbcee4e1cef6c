#pragma once
// The paper's evaluation (section 5, figures 8 and 9) on the simulator: for
// every scene x noise x contrast x seed, render with the desktop rig, decode
// with the graph decoder and with the DP baseline, and score both against the
// ground truth. docs/evaluation.md explains the method and shows the results.

#include "hal/sim/scene/scene.hpp"
#include "pipeline/decoder.hpp"
#include "pipeline/dp/dp_decoder.hpp"
#include "pipeline/rig.hpp"
#include "pipeline/status.hpp"

#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace stria::firmware {

struct EvaluationConfig {
    std::vector<hal::sim::SceneKind> scenes{hal::sim::SceneKind::TexturedRelief};
    std::optional<hal::sim::Albedo> albedo;  // empty: each scene's hal::sim::defaultAlbedo
    std::vector<double> noise{0, 2, 4, 8, 16};          // sigma of additive Gaussian noise, 8-bit digits
    std::vector<double> contrast{1, 0.7, 0.5, 0.3, 0.2};
    int seeds = 1;  // scene and noise seeds 1..seeds
    pipeline::DpParams dp;  // the baseline's parameters (Zhang et al.'s by default)

    // The quick subset of `stria eval --quick`.
    static EvaluationConfig quick();
    Status validate() const;
    int frames() const;
};

// How one decoder did on one frame. Errors are measured along the camera ray
// of each point, signed (positive = too far), against the rendered surface.
struct MethodScore {
    bool available = false;
    std::string unavailableReason;  // why, when not available
    long points = 0;
    long inliers = 0;   // |error| <= 1% of the working distance
    long outliers = 0;  // the rest, including points where there is no surface
    double meanErrorMm = 0, stdDevMm = 0;  // over the inliers (0 when there are none)
    double decodeMs = 0;                   // wall time of decode()
};

struct EvaluationRow {
    hal::sim::SceneKind scene{};
    hal::sim::Albedo albedo{};
    double noise = 0, contrast = 1;
    int seed = 1;
    long ideal = 0;  // idealEdgeCrossings: what a perfect decoder finds
    MethodScore graph, dp;
};

// Called after every frame with the number of frames done and in total.
using EvaluationProgress = std::function<void(int done, int total)>;

// Runs the whole sweep. Fails only when the sweep cannot run at all (bad
// config, the DP baseline cannot be built, a rendering fails); a graph
// decoder that cannot be built or fails on a frame is marked unavailable.
Result<std::vector<EvaluationRow>> runEvaluation(const EvaluationConfig& config,
                                                 const EvaluationProgress& progress = {});

// Scores points against a rendering of the same rig.
MethodScore scorePoints(std::span<const pipeline::ScanPoint> points, const hal::sim::Rendering& truth,
                        const pipeline::RigModel& rig, double inlierToleranceMm);

// The CSV (header + one line per row); unavailable methods have empty
// fields, and so have the mean error and deviation of a method without inliers.
extern const char* const kEvaluationCsvHeader;
std::string evaluationCsv(std::span<const EvaluationRow> rows);

}  // namespace stria::firmware
