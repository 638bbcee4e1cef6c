#pragma once
// Scores a decode against the simulator's ground truth, as the evaluation
// does: the error of a point is its distance to the true surface along its
// camera ray; an inlier is within 1% of the working distance.
#include "hal/sim/scene/scene.hpp"
#include "pipeline/decoder.hpp"

#include <span>

namespace stria::test {

struct Score {
    int points = 0, inliers = 0, outliers = 0, ideal = 0;
    double meanError = 0, stdError = 0;  // signed, mm, over inliers (measured - true along the ray)
    double inlierRatio() const { return ideal > 0 ? static_cast<double>(inliers) / ideal : 0; }
    double outlierRatio() const { return points > 0 ? static_cast<double>(outliers) / points : 0; }
};

Score scoreDecode(std::span<const pipeline::ScanPoint> points, const hal::sim::Rendering& truth,
                  const hal::sim::SimRig& rig);

}  // namespace stria::test
