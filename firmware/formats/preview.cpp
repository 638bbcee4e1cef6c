#include "firmware/formats/preview.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace stria::firmware {
namespace {

constexpr int kBarHeight = 44;  // scale bar strip below the image
// A decoded depth map has values only at stripe edges (~7 px apart along a
// row). For display, gaps up to this long between two measured pixels of one
// row whose depths differ by less than kFillJump are filled linearly, so the
// picture reads as a surface, as in the paper's figures; the data are not.
constexpr int kFillGap = 16;
constexpr double kFillJump = 0.02;

// Near = red ... far = blue, through yellow, green and cyan (a turbo-like
// ramp without the dark ends, so every valid pixel stays distinguishable from
// the black "no data").
cv::Vec3b rampColour(double f)
{
    f = std::clamp(f, 0.0, 1.0);
    // Hue from 0 (red) to 240 degrees (blue); OpenCV 8-bit hue is degrees / 2.
    cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(f * 120.0, 255, 255)), bgr;
    cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
    return bgr.at<cv::Vec3b>(0, 0);
}

bool valid(float z) { return std::isfinite(z) && z > 0; }

}  // namespace

cv::Mat depthPreview(const cv::Mat& depth, double nearMm, double farMm)
{
    CV_Assert(depth.type() == CV_32FC1);
    if (!(nearMm < farMm)) {
        std::vector<float> values;
        for (int y = 0; y < depth.rows; ++y)
            for (int x = 0; x < depth.cols; ++x)
                if (valid(depth.at<float>(y, x))) values.push_back(depth.at<float>(y, x));
        if (values.empty()) {
            nearMm = 0;
            farMm = 1;
        } else {
            auto at = [&](double q) {
                auto it = values.begin() + static_cast<std::ptrdiff_t>(q * (values.size() - 1));
                std::nth_element(values.begin(), it, values.end());
                return static_cast<double>(*it);
            };
            nearMm = at(0.02);
            farMm = at(0.98);
            if (!(farMm > nearMm)) farMm = nearMm + 1;
        }
    }
    std::vector<cv::Vec3b> lut(256);
    for (int i = 0; i < 256; ++i) lut[i] = rampColour(i / 255.0);

    const int width = std::max(depth.cols, 240);
    cv::Mat out(depth.rows + kBarHeight, width, CV_8UC3, cv::Scalar(0, 0, 0));
    auto paint = [&](int x, int y, double z) {
        out.at<cv::Vec3b>(y, x) =
            lut[static_cast<int>(std::lround(255.0 * std::clamp((z - nearMm) / (farMm - nearMm), 0.0, 1.0)))];
    };
    for (int y = 0; y < depth.rows; ++y) {
        const float* row = depth.ptr<float>(y);
        int last = -1;
        for (int x = 0; x < depth.cols; ++x) {
            if (!valid(row[x])) continue;
            paint(x, y, row[x]);
            if (last >= 0 && x - last <= kFillGap && std::abs(row[x] - row[last]) < kFillJump * row[x])
                for (int i = last + 1; i < x; ++i) paint(i, y, row[last] + (row[x] - row[last]) * (i - last) / (x - last));
            last = x;
        }
    }

    // Scale bar: the ramp with its ends and middle labelled in mm.
    const int barLeft = 10, barRight = width - 10, barTop = depth.rows + 6, barBottom = barTop + 12;
    for (int x = barLeft; x < barRight; ++x) {
        const cv::Vec3b c = lut[(x - barLeft) * 255 / std::max(1, barRight - barLeft - 1)];
        cv::line(out, {x, barTop}, {x, barBottom}, cv::Scalar(c[0], c[1], c[2]));
    }
    const cv::Scalar white(255, 255, 255);
    auto label = [&](double value, int x, int align) {
        char text[32];
        std::snprintf(text, sizeof text, "%.1f mm", value);
        int baseline = 0;
        const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline);
        const int left = align < 0 ? x : align > 0 ? x - size.width : x - size.width / 2;
        cv::putText(out, text, {left, barBottom + 4 + size.height}, cv::FONT_HERSHEY_SIMPLEX, 0.45, white, 1, cv::LINE_AA);
    };
    label(nearMm, barLeft, -1);
    label(0.5 * (nearMm + farMm), (barLeft + barRight) / 2, 0);
    label(farMm, barRight, 1);
    return out;
}

}  // namespace stria::firmware
