#include "firmware/app/evaluation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace stria::firmware {

using hal::sim::Rendering;
using pipeline::ScanPoint;

namespace {

// Depth of the rendered surface at sub-pixel column x of row y: linear
// between the two pixel centres when both see the same surface (within 2%,
// the rule idealEdgeCrossings uses), else the nearer centre's; NaN where
// nothing was rendered.
double surfaceDepth(const cv::Mat& depth, double x, int y)
{
    const int x0 = std::clamp(static_cast<int>(std::floor(x)), 0, depth.cols - 1);
    const int x1 = std::min(x0 + 1, depth.cols - 1);
    const double f = std::clamp(x - x0, 0.0, 1.0);
    const double d0 = depth.at<float>(y, x0), d1 = depth.at<float>(y, x1);
    if (std::isfinite(d0) && std::isfinite(d1) && std::abs(d0 - d1) <= 0.02 * 0.5 * (d0 + d1))
        return d0 + f * (d1 - d0);
    return f < 0.5 ? d0 : d1;
}

template <typename Decode>
MethodScore timeAndScore(Decode&& decode, const Rendering& rendering, const pipeline::RigModel& rig,
                         double toleranceMm)
{
    const FrameView frame{rendering.image.data, rendering.image.cols, rendering.image.rows,
                          static_cast<std::ptrdiff_t>(rendering.image.step), PixelFormat::Bgr8};
    const auto start = std::chrono::steady_clock::now();
    auto result = decode(frame);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!result) {
        MethodScore failed;
        failed.unavailableReason = result.message();
        return failed;
    }
    MethodScore score = scorePoints(result->points, rendering, rig, toleranceMm);
    score.decodeMs = ms;
    return score;
}

void appendMethod(std::string& line, const MethodScore& s)
{
    char buffer[160];
    if (!s.available) {
        line += ",0,,,,,,";
        return;
    }
    std::snprintf(buffer, sizeof buffer, ",1,%ld,%ld,%ld", s.points, s.inliers, s.outliers);
    line += buffer;
    if (s.inliers > 0) {
        std::snprintf(buffer, sizeof buffer, ",%.4f,%.4f", s.meanErrorMm, s.stdDevMm);
        line += buffer;
    } else {
        line += ",,";  // no inliers: no error statistics
    }
    std::snprintf(buffer, sizeof buffer, ",%.2f", s.decodeMs);
    line += buffer;
}

}  // namespace

EvaluationConfig EvaluationConfig::quick()
{
    EvaluationConfig config;
    config.noise = {2, 8};
    config.contrast = {1, 0.5};
    return config;
}

Status EvaluationConfig::validate() const
{
    if (scenes.empty()) return Status::error("no scenes to evaluate");
    if (noise.empty() || contrast.empty()) return Status::error("no noise or contrast levels to evaluate");
    for (double n : noise)
        if (!(n >= 0 && n <= 128)) return Status::error("noise sigma " + std::to_string(n) + " is not in [0, 128]");
    for (double c : contrast)
        if (!(c > 0 && c <= 1)) return Status::error("contrast " + std::to_string(c) + " is not in (0, 1]");
    if (seeds < 1 || seeds > 1000) return Status::error("seeds must be 1..1000, not " + std::to_string(seeds));
    return dp.validate();
}

int EvaluationConfig::frames() const
{
    return static_cast<int>(scenes.size() * noise.size() * contrast.size()) * seeds;
}

MethodScore scorePoints(std::span<const ScanPoint> points, const Rendering& truth, const pipeline::RigModel& rig,
                        double inlierToleranceMm)
{
    MethodScore score;
    score.available = true;
    score.points = static_cast<long>(points.size());
    double sum = 0, sumSquares = 0;
    for (const ScanPoint& p : points) {
        const int row = static_cast<int>(std::lround(p.pixel.y));
        double error = NAN;
        if (row >= 0 && row < truth.depth.rows && p.pixel.x >= 0 && p.pixel.x <= truth.depth.cols - 1) {
            const cv::Vec3d ray = rig.camera().rayThroughPixel({p.pixel.x, p.pixel.y});
            error = (p.position[2] - surfaceDepth(truth.depth, p.pixel.x, row)) * cv::norm(ray);
        }
        if (std::abs(error) <= inlierToleranceMm) {  // false for NaN
            ++score.inliers;
            sum += error;
            sumSquares += error * error;
        } else {
            ++score.outliers;
        }
    }
    if (score.inliers > 0) {
        const auto n = static_cast<double>(score.inliers);
        score.meanErrorMm = sum / n;
        score.stdDevMm = std::sqrt(std::max(0.0, sumSquares / n - score.meanErrorMm * score.meanErrorMm));
    }
    return score;
}

Result<std::vector<EvaluationRow>> runEvaluation(const EvaluationConfig& config, const EvaluationProgress& progress)
{
    if (Status s = config.validate(); !s) return s;
    const hal::sim::SimRig simRig = hal::sim::desktopRig();
    const double toleranceMm = 0.01 * simRig.workingDistanceMm;
    const hal::sim::SceneRenderer renderer(simRig);

    auto dp = pipeline::DpDecoder::create(simRig.pattern, simRig.rig, config.dp);
    if (!dp) return dp.status().withContext("DP baseline: ");
    auto graph = pipeline::Decoder::create(simRig.pattern, simRig.rig);
    const std::string graphMissing = graph ? "" : "graph decoder: " + graph.message();

    std::vector<EvaluationRow> rows;
    rows.reserve(static_cast<std::size_t>(config.frames()));
    Rendering rendering;
    for (hal::sim::SceneKind kind : config.scenes)
        for (int seed = 1; seed <= config.seeds; ++seed) {
            const hal::sim::Albedo albedo = config.albedo.value_or(hal::sim::defaultAlbedo(kind));
            const hal::sim::Scene scene = hal::sim::makeScene(kind, simRig, albedo, static_cast<std::uint64_t>(seed));
            for (double contrast : config.contrast)
                for (double noise : config.noise) {
                    hal::sim::RenderSettings settings;
                    settings.contrast = contrast;
                    settings.noiseSigma = noise;
                    settings.seed = static_cast<std::uint64_t>(seed);
                    if (Status s = renderer.render(scene, settings, rendering); !s)
                        return s.withContext(std::string("rendering scene '") + hal::sim::sceneName(kind) + "': ");
                    EvaluationRow row;
                    row.scene = kind;
                    row.albedo = albedo;
                    row.noise = noise;
                    row.contrast = contrast;
                    row.seed = seed;
                    row.ideal = hal::sim::idealEdgeCrossings(rendering, simRig.pattern);
                    if (graph) {
                        row.graph = timeAndScore([&](const FrameView& f) { return (*graph)->decode(f); }, rendering,
                                                 simRig.rig, toleranceMm);
                    } else {
                        row.graph.unavailableReason = graphMissing;
                    }
                    row.dp = timeAndScore([&](const FrameView& f) { return (*dp)->decode(f); }, rendering,
                                          simRig.rig, toleranceMm);
                    if (!row.dp.available) return Status::error("DP baseline: " + row.dp.unavailableReason);
                    rows.push_back(row);
                    if (progress) progress(static_cast<int>(rows.size()), config.frames());
                }
        }
    return rows;
}

const char* const kEvaluationCsvHeader =
    "scene,albedo,noise,contrast,seed,ideal,"
    "graph_available,graph_points,graph_inliers,graph_outliers,graph_mean_error_mm,graph_std_dev_mm,graph_decode_ms,"
    "dp_available,dp_points,dp_inliers,dp_outliers,dp_mean_error_mm,dp_std_dev_mm,dp_decode_ms";

std::string evaluationCsv(std::span<const EvaluationRow> rows)
{
    std::string csv = std::string(kEvaluationCsvHeader) + "\n";
    for (const EvaluationRow& row : rows) {
        char buffer[160];
        std::snprintf(buffer, sizeof buffer, "%s,%s,%g,%g,%d,%ld", hal::sim::sceneName(row.scene),
                      hal::sim::albedoName(row.albedo), row.noise, row.contrast, row.seed, row.ideal);
        std::string line = buffer;
        appendMethod(line, row.graph);
        appendMethod(line, row.dp);
        csv += line + "\n";
    }
    return csv;
}

}  // namespace stria::firmware
