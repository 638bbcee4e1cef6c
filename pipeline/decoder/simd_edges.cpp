// Edge location kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#include <cstring>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace stria::pipeline {

void projectedGradientsReference(const std::uint8_t* row, int first, int count, const std::array<int, 3>& rgbOffset,
                                 const cv::Matx33f& m, const cv::Vec3f& weight, float* out)
{
    for (int k = 0; k < count; ++k) {
        const std::uint8_t* p = row + 3 * (first + k);
        const cv::Vec3f raw(static_cast<float>(p[3 + rgbOffset[0]] - p[rgbOffset[0]]),
                            static_cast<float>(p[3 + rgbOffset[1]] - p[rgbOffset[1]]),
                            static_cast<float>(p[3 + rgbOffset[2]] - p[rgbOffset[2]]));
        out[k] = weight.dot(m * raw);
    }
}

void projectedGradients(const std::uint8_t* row, int first, int count, const std::array<int, 3>& rgbOffset,
                        const cv::Matx33f& m, const cv::Vec3f& weight, float* out)
{
    int k = 0;
#if defined(__ARM_NEON)
    // 8 samples per step: pixels i..i+7 and i+1..i+8 de-interleaved. Products
    // and sums one by one from 0 as cv::Matx computes them (no fused
    // multiply-add), so every lane equals the reference bit for bit.
    for (; k + 8 <= count; k += 8) {
        const int i = first + k;
        const uint8x8x3_t here = vld3_u8(row + 3 * i), next = vld3_u8(row + 3 * (i + 1));
        for (int half = 0; half < 2; ++half) {
            float32x4_t raw[3];
            for (int c = 0; c < 3; ++c) {
                const int16x8_t d = vreinterpretq_s16_u16(vsubl_u8(next.val[rgbOffset[c]], here.val[rgbOffset[c]]));
                raw[c] = vcvtq_f32_s32(vmovl_s16(half == 0 ? vget_low_s16(d) : vget_high_s16(d)));
            }
            float32x4_t sum = vdupq_n_f32(0);
            for (int r = 0; r < 3; ++r) {
                float32x4_t corrected = vdupq_n_f32(0);
                for (int c = 0; c < 3; ++c) corrected = vaddq_f32(corrected, vmulq_n_f32(raw[c], m(r, c)));
                sum = vaddq_f32(sum, vmulq_n_f32(corrected, weight[r]));
            }
            vst1q_f32(out + k + 4 * half, sum);
        }
    }
#else
    // 4 samples per step in GCC vector lanes (exact IEEE float per lane):
    // the reference's products and sums in its order, each sum from 0. A
    // ragged end is one more step ending at the last sample (the overlapping
    // samples are written twice with the same values).
    using Int4 = std::int32_t __attribute__((vector_size(16)));
    using Float4 = float __attribute__((vector_size(16)));
    const Float4 zero = {0, 0, 0, 0};
    // Lanes of m and weight built once per call, not per step (the stores
    // to out could alias m and weight, so the compiler reloaded them).
    Float4 mm[3][3], ww[3];
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) mm[r][c] = Float4{m(r, c), m(r, c), m(r, c), m(r, c)};
        ww[r] = Float4{weight[r], weight[r], weight[r], weight[r]};
    }
    const std::array<int, 3> o = rgbOffset;
    auto step = [&](int k) {
        const std::uint8_t* p = row + 3 * (first + k);
        Float4 raw[3];
        for (int c = 0; c < 3; ++c) {
            const std::uint8_t* q = p + o[c];
            const Int4 d = {q[3] - q[0], q[6] - q[3], q[9] - q[6], q[12] - q[9]};
            raw[c] = __builtin_convertvector(d, Float4);
        }
        Float4 sum = zero;
        for (int r = 0; r < 3; ++r) {
            const Float4 corrected = zero + mm[r][0] * raw[0] + mm[r][1] * raw[1] + mm[r][2] * raw[2];
            sum = sum + ww[r] * corrected;
        }
        std::memcpy(out + k, &sum, sizeof sum);
    };
    for (; k + 4 <= count; k += 4) step(k);
    if (k < count && count >= 4) {
        step(count - 4);
        return;
    }
#endif
    if (k < count) projectedGradientsReference(row, first + k, count - k, rgbOffset, m, weight, out + k);
}

}  // namespace stria::pipeline
