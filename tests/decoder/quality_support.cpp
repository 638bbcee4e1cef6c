#include "tests/decoder/quality_support.hpp"

#include "firmware/app/evaluation.hpp"

namespace stria::test {

// The evaluation's scoring (firmware/app/evaluation.cpp) is the one definition
// of inlier and outlier; the quality tests only add the ideal count.
Score scoreDecode(std::span<const pipeline::ScanPoint> points, const hal::sim::Rendering& truth,
                  const hal::sim::SimRig& rig)
{
    const firmware::MethodScore s = firmware::scorePoints(points, truth, rig.rig, 0.01 * rig.workingDistanceMm);
    Score score;
    score.points = static_cast<int>(s.points);
    score.inliers = static_cast<int>(s.inliers);
    score.outliers = static_cast<int>(s.outliers);
    score.meanError = s.meanErrorMm;
    score.stdError = s.stdDevMm;
    score.ideal = hal::sim::idealEdgeCrossings(truth, rig.pattern);
    return score;
}

}  // namespace stria::test
