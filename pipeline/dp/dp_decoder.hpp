#pragma once
// The scanline dynamic-programming decoder of Zhang, Curless and Seitz (2002,
// "Rapid shape acquisition using color structured light and multi-pass
// dynamic programming"), the baseline the paper's graph decoder is compared
// with. Each camera row is decoded on its own:
//
//  1. Observed transitions: local maxima of the 1-D colour gradient magnitude
//     along the row above a floor, each with its colour change vector e
//     (intensities in [0, 1], channels R G B).
//  2. Score of matching e with a pattern transition q (per channel -1, 0, +1):
//       consistent(+1, e) = clamp((e - alpha) / (beta - alpha), -1, 1)
//       consistent(-1, e) = clamp((-e - alpha) / (beta - alpha), -1, 1)
//       consistent( 0, e) = clamp(1 - (|e| - alpha) / (beta - alpha), -1, 1)
//       score(q, e)       = min over channels of consistent(q_k, e_k)
//     A channel expected to rise scores 1 once it rises by beta and -1 once it
//     falls by 2 alpha - beta; a channel expected to stay scores 1 below alpha.
//  3. Dynamic programming maximises the summed score over monotonic matchings
//     (the ordering constraint) of observed to pattern transitions; both sides
//     may be skipped at no cost, so only positive scores are ever taken. Ties,
//     which the score leaves many of, go to runs of consecutive pattern edges
//     (a bonus of 1e-3 per continued pair; see runPass).
//  4. Multi-pass: the matched pairs are removed and the DP runs again on what
//     is left of both sequences, which recovers pieces whose order is swapped
//     (a foreground object in front of the background), until a pass adds
//     nothing or `passes` is reached.
//
// Points are made as the graph decoder makes them: the edge is located to
// sub-pixel precision along the row and triangulated with the light plane of
// its pattern edge.

#include "pipeline/decoder.hpp"
#include "pipeline/frame.hpp"
#include "pipeline/pattern.hpp"
#include "pipeline/rig.hpp"
#include "pipeline/status.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace stria::pipeline {

struct DpParams {
    // Zhang et al.'s ramp, on intensities in [0, 1].
    double alpha = 0.007;
    double beta = 0.03;
    // A local maximum of the gradient magnitude (L2 over the channels of
    // I(x+1) - I(x-1)) is a candidate transition when it reaches this: a
    // "small floor" at beta, where a channel's rise first scores fully.
    double edgeFloor = 0.03;
    // The colour change is taken between the pixels this far left and right of
    // the edge, outside the blur of the edge itself.
    int sideOffset = 2;
    // Passes of the multi-pass DP (1 = plain DP).
    int passes = 3;

    Status validate() const;
};

// One matched transition of one row, before triangulation (decodeRow).
struct DpMatch {
    float x = 0;      // sub-pixel camera column of the edge
    int edge = 0;     // pattern edge index
    float score = 0;  // in (0, 1]
    int pass = 0;     // 0-based pass that matched it
};

class DpDecoder {
public:
    static Result<std::unique_ptr<DpDecoder>> create(const StripePattern& pattern, const RigModel& rig,
                                                     const DpParams& params = {});

    // frame: BGR8 or RGB8, exactly the calibrated camera size. The points are
    // valid until the next decode(); only `points` and `timings.totalMs` of
    // the result are filled. Unlike Decoder, it allocates as rows need.
    Result<DecodeResult> decode(const FrameView& frame);

    // Depth (z, mm) of the last decode into a CV_32FC1 of camera size, NaN
    // where nothing was measured (as Decoder::fillDepthMap).
    void fillDepthMap(cv::Mat& depth) const;

    // The matches of one row (row must be inside the frame), sorted by x.
    Result<std::vector<DpMatch>> decodeRow(const FrameView& frame, int row);

    const DpParams& params() const { return params_; }

private:
    struct Observed {
        float x = 0;                            // sub-pixel position
        std::array<float, kSymbolCount> score;  // score against every symbol
    };

    DpDecoder(const DpParams& params, const RigModel& rig) : params_(params), rig_(rig) {}
    Status checkFrame(const FrameView& frame) const;
    void findTransitions(const FrameView& frame, int row);
    void matchRow(std::vector<DpMatch>& matches);
    // One DP pass over the unmatched transitions; returns the pairs it matched.
    int runPass(int pass, std::vector<DpMatch>& matches);

    DpParams params_;
    RigModel rig_;
    std::vector<SymbolCode> symbols_;  // pattern edge symbols
    std::vector<Plane> planes_;        // light plane of every pattern edge
    std::vector<ScanPoint> points_;    // the last decode's points

    // Per-row scratch, reused from row to row.
    std::vector<float> rgb_;        // the row as R G B floats in [0, 1]
    std::vector<float> magnitude_;  // gradient magnitude per column
    std::vector<Observed> observed_;
    std::vector<std::uint8_t> observedUsed_, edgeUsed_;
    std::vector<int> observedLeft_, edgesLeft_;  // indices still unmatched
    std::vector<float> best_, run_;              // (n + 1) x (m + 1) DP tables of a pass
    std::vector<std::uint8_t> choice_;           // back-pointers of best_ and run_
};

}  // namespace stria::pipeline
