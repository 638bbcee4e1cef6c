// Edge location kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
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
#elif defined(__SSE2__)
    // 4 samples per step, the reference's products and sums in its order,
    // each sum from 0 (exact IEEE float per lane). The bytes of pixels
    // i..i+4 come in two 8-byte loads (p[0..7], p[7..14]: nothing past the
    // last pixel), their differences p[j + 3] - p[j] as 12 int16 lanes, and
    // shuffles pick each channel's 4 (byte j = 3 x sample + channel): 28
    // instructions instead of 57 for 12 single byte loads per channel. A
    // ragged end is one more step ending at the last sample (the overlapping
    // samples are written twice with the same values).
    // Lanes of m and weight built once per call, not per step (the stores
    // to out could alias m and weight, so the compiler reloaded them).
    __m128 mm[3][3], ww[3];
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) mm[r][c] = _mm_set1_ps(m(r, c));
        ww[r] = _mm_set1_ps(weight[r]);
    }
    const std::array<int, 3> o = rgbOffset;
    const __m128i zero = _mm_setzero_si128();
    auto toFloat = [](__m128i int16x4) { return _mm_cvtepi32_ps(_mm_srai_epi32(_mm_unpacklo_epi16(int16x4, int16x4), 16)); };
    auto step = [&](int k) {
        const std::uint8_t* p = row + 3 * (first + k);
        const __m128i a = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), zero);
        const __m128i b = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + 7)), zero);
        // p[3..10]: a's lanes 3..7, then b's 1..3 (lane 4 gets p[7] from both).
        const __m128i shifted = _mm_or_si128(_mm_srli_si128(a, 6), _mm_slli_si128(b, 8));
        const __m128i low = _mm_sub_epi16(shifted, a);                                     // j = 0..7
        const __m128i high = _mm_sub_epi16(_mm_srli_si128(b, 8), _mm_srli_si128(b, 2));  // j = 8..11
        const __m128 d0 = toFloat(low), d1 = toFloat(_mm_srli_si128(low, 8)), d2 = toFloat(high);
        __m128 channel[3];  // byte b of each pixel: j = b, b + 3, b + 6, b + 9
        channel[0] = _mm_shuffle_ps(d0, _mm_shuffle_ps(d1, d2, _MM_SHUFFLE(0, 1, 0, 2)), _MM_SHUFFLE(2, 0, 3, 0));
        channel[1] = _mm_shuffle_ps(_mm_shuffle_ps(d0, d1, _MM_SHUFFLE(0, 0, 0, 1)),
                                    _mm_shuffle_ps(d1, d2, _MM_SHUFFLE(0, 2, 0, 3)), _MM_SHUFFLE(2, 0, 2, 0));
        channel[2] = _mm_shuffle_ps(_mm_shuffle_ps(d0, d1, _MM_SHUFFLE(0, 1, 0, 2)), d2, _MM_SHUFFLE(3, 0, 2, 0));
        const __m128 raw[3] = {channel[o[0]], channel[o[1]], channel[o[2]]};
        __m128 sum = _mm_setzero_ps();
        for (int r = 0; r < 3; ++r) {
            __m128 corrected = _mm_setzero_ps();
            for (int c = 0; c < 3; ++c) corrected = _mm_add_ps(corrected, _mm_mul_ps(mm[r][c], raw[c]));
            sum = _mm_add_ps(sum, _mm_mul_ps(ww[r], corrected));
        }
        _mm_storeu_ps(out + k, sum);
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
