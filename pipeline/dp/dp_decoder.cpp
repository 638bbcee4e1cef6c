#include "pipeline/dp/dp_decoder.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

namespace stria::pipeline {
namespace {

// choice_ bits: how best_(i, j) was reached, and whether run_(i, j) extends run_(i-1, j-1).
constexpr std::uint8_t kMatch = 0, kSkipObserved = 1, kSkipPattern = 2, kMoveMask = 3, kContinuesRun = 4;

float consistency(int expected, float change, float alpha, float beta)
{
    const float ramp = beta - alpha;
    float v;
    if (expected > 0)
        v = (change - alpha) / ramp;
    else if (expected < 0)
        v = (-change - alpha) / ramp;
    else
        v = 1.0f - (std::abs(change) - alpha) / ramp;
    return std::clamp(v, -1.0f, 1.0f);
}

}  // namespace

Status DpParams::validate() const
{
    if (!(alpha >= 0 && beta > alpha && beta <= 1))
        return Status::error("DP ramp needs 0 <= alpha < beta <= 1, got alpha " + std::to_string(alpha) + ", beta " +
                             std::to_string(beta));
    if (!(edgeFloor > 0 && edgeFloor < 1))
        return Status::error("DP edge floor must be in (0, 1), got " + std::to_string(edgeFloor));
    if (sideOffset < 1 || sideOffset > 16)
        return Status::error("DP side offset must be 1..16 px, got " + std::to_string(sideOffset));
    if (passes < 1 || passes > 16) return Status::error("DP passes must be 1..16, got " + std::to_string(passes));
    return Status::ok();
}

Result<std::unique_ptr<DpDecoder>> DpDecoder::create(const StripePattern& pattern, const RigModel& rig,
                                                     const DpParams& params)
{
    if (Status s = params.validate(); !s) return s;
    std::unique_ptr<DpDecoder> decoder(new DpDecoder(params, rig));
    decoder->symbols_.assign(pattern.edgeSymbols().begin(), pattern.edgeSymbols().end());
    decoder->planes_.reserve(decoder->symbols_.size());
    for (int edge = 0; edge < pattern.edgeCount(); ++edge)
        decoder->planes_.push_back(rig.lightPlaneForColumn(pattern.edgeColumn(edge)));
    return decoder;
}

Status DpDecoder::checkFrame(const FrameView& frame) const
{
    if (frame.empty()) return Status::error("DP decoder: empty frame");
    if (frame.format != PixelFormat::Bgr8 && frame.format != PixelFormat::Rgb8)
        return Status::error(std::string("DP decoder: pixel format ") + pixelFormatName(frame.format) +
                             " is not supported (Bgr8 or Rgb8)");
    const LensModel& camera = rig_.camera();
    if (frame.width != camera.width || frame.height != camera.height)
        return Status::error("DP decoder: frame is " + std::to_string(frame.width) + "x" +
                             std::to_string(frame.height) + " but the camera is " + std::to_string(camera.width) +
                             "x" + std::to_string(camera.height));
    return Status::ok();
}

void DpDecoder::findTransitions(const FrameView& frame, int row)
{
    const int width = frame.width;
    const bool bgr = frame.format == PixelFormat::Bgr8;
    rgb_.resize(static_cast<std::size_t>(width) * 3);
    const std::uint8_t* src = frame.row(row);
    for (int x = 0; x < width; ++x) {
        const std::uint8_t* p = src + 3 * x;
        rgb_[3 * x + kRed] = p[bgr ? 2 : 0] / 255.0f;
        rgb_[3 * x + kGreen] = p[1] / 255.0f;
        rgb_[3 * x + kBlue] = p[bgr ? 0 : 2] / 255.0f;
    }

    // Central difference over two pixels: a sharp step of height h reads h.
    magnitude_.assign(static_cast<std::size_t>(width), 0.0f);
    for (int x = 1; x + 1 < width; ++x) {
        float sum = 0;
        for (int c = 0; c < 3; ++c) {
            const float d = rgb_[3 * (x + 1) + c] - rgb_[3 * (x - 1) + c];
            sum += d * d;
        }
        magnitude_[x] = std::sqrt(sum);
    }

    observed_.clear();
    const int r = params_.sideOffset;
    const auto alpha = static_cast<float>(params_.alpha);
    const auto beta = static_cast<float>(params_.beta);
    const auto floor = static_cast<float>(params_.edgeFloor);
    for (int x = std::max(r, 2); x + std::max(r, 2) < width; ++x) {
        const float m = magnitude_[x];
        if (m < floor || !(m > magnitude_[x - 1] && m >= magnitude_[x + 1])) continue;
        // Parabola through the maximum and its neighbours, as the graph
        // decoder locates its edges.
        const float left = magnitude_[x - 1], right = magnitude_[x + 1];
        const float curvature = left - 2 * m + right;
        const float offset = curvature < 0 ? 0.5f * (left - right) / curvature : 0.0f;
        Observed o;
        o.x = static_cast<float>(x) + std::clamp(offset, -0.5f, 0.5f);
        float change[3];
        for (int c = 0; c < 3; ++c) change[c] = rgb_[3 * (x + r) + c] - rgb_[3 * (x - r) + c];
        for (int s = 0; s < kSymbolCount; ++s) {
            const auto symbol = static_cast<SymbolCode>(s);
            float score = 1.0f;
            for (int c = 0; c < 3; ++c)
                score = std::min(score, consistency(symbolChannel(symbol, c), change[c], alpha, beta));
            o.score[s] = score;
        }
        observed_.push_back(o);
    }
}

int DpDecoder::runPass(int pass, std::vector<DpMatch>& matches)
{
    observedLeft_.clear();
    edgesLeft_.clear();
    for (int i = 0; i < static_cast<int>(observed_.size()); ++i)
        if (!observedUsed_[i]) observedLeft_.push_back(i);
    for (int j = 0; j < static_cast<int>(symbols_.size()); ++j)
        if (!edgeUsed_[j]) edgesLeft_.push_back(j);
    const int n = static_cast<int>(observedLeft_.size());
    const int m = static_cast<int>(edgesLeft_.size());
    if (n == 0 || m == 0) return 0;

    // best_(i, j): best matching of the first i observed and j pattern
    // transitions; run_(i, j): the same with observed i matched to pattern j
    // (-inf when their score is not positive). Among equal totals a matched
    // pair that continues a run of consecutive pairs wins by kRunBonus: the
    // score alone leaves many ties (a transition matches every pattern edge
    // of its symbol equally), and the contiguous reading is the one meant.
    constexpr float kRunBonus = 1e-3f;
    constexpr float kNone = -1e30f;
    const std::size_t stride = static_cast<std::size_t>(m) + 1;
    best_.assign(static_cast<std::size_t>(n + 1) * stride, 0.0f);
    run_.assign(static_cast<std::size_t>(n + 1) * stride, kNone);
    choice_.resize(static_cast<std::size_t>(n + 1) * stride);
    for (int i = 1; i <= n; ++i) {
        const Observed& o = observed_[observedLeft_[i - 1]];
        const std::size_t above = (i - 1) * stride, here = i * stride;
        for (int j = 1; j <= m; ++j) {
            std::uint8_t how = kSkipObserved;
            const float s = o.score[symbols_[edgesLeft_[j - 1]]];
            if (s > 0) {
                const float continued = run_[above + j - 1] + kRunBonus;
                const float fresh = best_[above + j - 1];
                run_[here + j] = s + std::max(continued, fresh);
                if (continued > fresh) how |= kContinuesRun;
            }
            float best = best_[above + j];
            if (best_[here + j - 1] > best) {
                best = best_[here + j - 1];
                how = static_cast<std::uint8_t>((how & kContinuesRun) | kSkipPattern);
            }
            if (run_[here + j] > best) {
                best = run_[here + j];
                how = static_cast<std::uint8_t>((how & kContinuesRun) | kMatch);
            }
            best_[here + j] = best;
            choice_[here + j] = how;
        }
    }

    int added = 0;
    bool inRun = false;  // at (i, j) in run_ rather than best_
    for (int i = n, j = m; i > 0 && j > 0;) {
        const std::uint8_t how = choice_[i * stride + j];
        if (!inRun && (how & kMoveMask) == kSkipObserved) {
            --i;
        } else if (!inRun && (how & kMoveMask) == kSkipPattern) {
            --j;
        } else {
            const int oi = observedLeft_[i - 1], edge = edgesLeft_[j - 1];
            observedUsed_[oi] = 1;
            edgeUsed_[edge] = 1;
            matches.push_back({observed_[oi].x, edge, observed_[oi].score[symbols_[edge]], pass});
            ++added;
            inRun = (how & kContinuesRun) != 0;
            --i;
            --j;
        }
    }
    return added;
}

void DpDecoder::matchRow(std::vector<DpMatch>& matches)
{
    observedUsed_.assign(observed_.size(), 0);
    edgeUsed_.assign(symbols_.size(), 0);
    for (int pass = 0; pass < params_.passes; ++pass)
        if (runPass(pass, matches) == 0) break;
}

Result<std::vector<DpMatch>> DpDecoder::decodeRow(const FrameView& frame, int row)
{
    if (Status s = checkFrame(frame); !s) return s;
    if (row < 0 || row >= frame.height)
        return Status::error("DP decoder: row " + std::to_string(row) + " is outside the frame (0.." +
                             std::to_string(frame.height - 1) + ")");
    std::vector<DpMatch> matches;
    findTransitions(frame, row);
    matchRow(matches);
    std::sort(matches.begin(), matches.end(), [](const DpMatch& a, const DpMatch& b) { return a.x < b.x; });
    return matches;
}

Result<DecodeResult> DpDecoder::decode(const FrameView& frame)
{
    if (Status s = checkFrame(frame); !s) return s;
    const auto start = std::chrono::steady_clock::now();
    points_.clear();
    std::vector<DpMatch> matches;
    for (int row = 0; row < frame.height; ++row) {
        matches.clear();
        findTransitions(frame, row);
        matchRow(matches);
        for (const DpMatch& match : matches) {
            const auto point = rig_.triangulate({match.x, static_cast<double>(row)}, planes_[match.edge]);
            if (!point) continue;
            points_.push_back({cv::Vec3f(*point), cv::Point2f(match.x, static_cast<float>(row)), match.edge});
        }
    }
    DecodeResult result;
    result.points = points_;
    result.timings.totalMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
}

void DpDecoder::fillDepthMap(cv::Mat& depth) const
{
    const LensModel& camera = rig_.camera();
    depth.create(camera.height, camera.width, CV_32FC1);
    depth.setTo(std::numeric_limits<float>::quiet_NaN());
    for (const ScanPoint& p : points_) {
        const int x = static_cast<int>(std::lround(p.pixel.x)), y = static_cast<int>(std::lround(p.pixel.y));
        if (x >= 0 && x < camera.width && y >= 0 && y < camera.height) depth.at<float>(y, x) = p.position[2];
    }
}

}  // namespace stria::pipeline
