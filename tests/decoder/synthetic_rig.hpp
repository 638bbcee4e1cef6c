#pragma once
// A rig whose camera sees the slide 1:1 (same size, no distortion, projector
// 100 mm beside the camera, principal points 50 px apart), so a rendered slide
// is the frame of a fronto-parallel plane at z = 100 * 500 / 50 = 1000 mm with
// known stripes: edge k lies exactly between camera pixels 8k+7 and 8k+8.
#include "pipeline/pattern.hpp"
#include "pipeline/rig.hpp"

namespace stria::test {

inline pipeline::RigModel slideRig(const pipeline::StripePattern& pattern, int height)
{
    pipeline::LensModel projector;
    projector.width = pattern.projectorColumnsUsed();
    projector.height = height;
    projector.K = cv::Matx33d(500, 0, (projector.width - 1) / 2.0, 0, 500, (height - 1) / 2.0, 0, 0, 1);
    pipeline::LensModel camera = projector;
    camera.K(0, 2) -= 50;
    return pipeline::RigModel::create(camera, projector, cv::Matx33d::eye(), cv::Vec3d(-100, 0, 0)).value();
}

inline pipeline::StripePattern slidePattern(int stripes = 40)
{
    return pipeline::StripePattern::generate(stripes, 4, 8, 7).value();
}

}  // namespace stria::test
