#pragma once
// The frames every benchmark decodes: the simulator's textured relief (the
// paper's kind of scene: a coloured, printed-photo-like surface with depth
// steps) seen by the desktop rig at 780x580 or 1388x1038, Gaussian noise
// sigma 4. Rendered once per process and size; rendering is not measured.
#include "hal/sim/scene/scene.hpp"
#include "pipeline/frame.hpp"

#include <opencv2/core.hpp>

#include <vector>

namespace stria::bench {

enum class FrameSize { Small /* 780x580 */, Large /* 1388x1038 */ };

struct BenchFrame {
    hal::sim::SimRig rig;
    hal::sim::Rendering rendering;  // image (BGR8) and ground truth
    cv::Mat grey;                   // the image in grey, for the grey Sobel reference
};

// Null if rendering failed (the message is printed).
const BenchFrame* benchFrame(FrameSize size);
// `count` frames of the small scene, each with its own noise seed (stream replay).
const std::vector<cv::Mat>& replayFrames(int count);

FrameView viewOf(const cv::Mat& image);

}  // namespace stria::bench
