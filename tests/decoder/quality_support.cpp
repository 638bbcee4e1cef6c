#include "tests/decoder/quality_support.hpp"

#include <cmath>

namespace stria::test {

Score scoreDecode(std::span<const pipeline::ScanPoint> points, const hal::sim::Rendering& truth,
                  const hal::sim::SimRig& rig)
{
    Score score;
    score.points = static_cast<int>(points.size());
    score.ideal = hal::sim::idealEdgeCrossings(truth, rig.pattern);
    const double limit = 0.01 * rig.workingDistanceMm;
    double sum = 0, sum2 = 0;
    for (const pipeline::ScanPoint& p : points) {
        // True depth at the sub-pixel position: linear between the two pixel
        // centres of the row; a point whose neighbours have no surface is an outlier.
        const int y = static_cast<int>(std::lround(p.pixel.y));
        const int x0 = static_cast<int>(std::floor(p.pixel.x));
        double error = 1e9;
        if (y >= 0 && y < truth.depth.rows && x0 >= 0 && x0 + 1 < truth.depth.cols) {
            const float z0 = truth.depth.at<float>(y, x0), z1 = truth.depth.at<float>(y, x0 + 1);
            const double f = p.pixel.x - x0;
            double z = std::nan("");
            if (std::isfinite(z0) && std::isfinite(z1) && std::abs(z0 - z1) < 0.02 * z0) z = z0 * (1 - f) + z1 * f;
            else if (std::isfinite(z0) && f < 0.5) z = z0;
            else if (std::isfinite(z1) && f >= 0.5) z = z1;
            if (std::isfinite(z)) {
                const cv::Vec3d ray = rig.rig.camera().rayThroughPixel({p.pixel.x, p.pixel.y});
                error = (p.position[2] - z) * cv::norm(ray);
            }
        }
        if (std::abs(error) <= limit) {
            ++score.inliers;
            sum += error;
            sum2 += error * error;
        } else {
            ++score.outliers;
        }
    }
    if (score.inliers > 0) {
        score.meanError = sum / score.inliers;
        score.stdError = std::sqrt(std::max(0.0, sum2 / score.inliers - score.meanError * score.meanError));
    }
    return score;
}

}  // namespace stria::test
