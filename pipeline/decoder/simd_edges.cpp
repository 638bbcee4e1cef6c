// Edge location kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#include <algorithm>
#include <limits>
#include <type_traits>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__)
#include <immintrin.h>
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

namespace {

// A window that the row's ends cut, or a channel order without a fast path:
// the reference over the samples inside the row.
void clippedWindow(const std::uint8_t* row, int width, int first, const std::array<int, 3>& rgbOffset,
                   const cv::Matx33f& m, const cv::Vec3f& weight, float* out)
{
    const int lo = std::max(first, 0), hi = std::min(first + kWindowSamples - 1, width - 2);
    std::fill(out, out + kWindowSamples, -std::numeric_limits<float>::infinity());
    if (lo <= hi) projectedGradientsReference(row, lo, hi - lo + 1, rgbOffset, m, weight, out + (lo - first));
}

// Whether the row's ends cut the window at `first` (first < 0 or first +
// kWindowSamples > width - 1), as one unsigned compare: first >= the end of
// the first columns of uncut windows (0 if none).
[[gnu::always_inline]] inline bool windowCut(int first, int width)
{
    return static_cast<unsigned>(first) >= static_cast<unsigned>(std::max(width - kWindowSamples, 0));
}

// The windows inside the row, for pixels in B G R (bgr) or R G B order
// (a template: the channel order is resolved at compile time, not by an
// index per step). Products summed without the reference's leading 0 + :
// that changes at most the sign of a zero sum, which no peak test or
// centroid sees, and saves 4 of 24 vector additions per 4 samples. Without
// crosstalk (m the identity: no crosstalk calibrated) the correction is
// skipped: 1 x a + 0 x b + 0 x c is a (up to a zero's sign), and it is 15
// of the 20 vector operations per 4 samples.
template <bool bgr, bool identity>
void windows(const std::uint8_t* row, int width, const std::int32_t* firsts, const cv::Vec3f* weights, int count,
             const std::array<int, 3>& rgbOffset, const cv::Matx33f& m, std::array<float, kWindowSamples + 1>* out)
{
#if defined(__ARM_NEON)
    for (int j = 0; j < count; ++j) {
        const int first = firsts[j];
        if (windowCut(first, width)) {
            clippedWindow(row, width, first, rgbOffset, m, weights[j], out[j].data());
            continue;
        }
        // Pixels first .. first + 7 and first + 1 .. first + 8, de-interleaved.
        const std::uint8_t* p = row + 3 * first;
        const uint8x8x3_t here = vld3_u8(p), next = vld3_u8(p + 3);
        constexpr int byte[3] = {bgr ? 2 : 0, 1, bgr ? 0 : 2};  // of R, G, B in a pixel
        // The weights loaded once (out[j] might alias them: GCC reloaded them for the second half).
        const float weight[3] = {weights[j][0], weights[j][1], weights[j][2]};
        for (int half = 0; half < 2; ++half) {
            float32x4_t raw[3];
            for (int c = 0; c < 3; ++c) {
                const int16x8_t d = vreinterpretq_s16_u16(vsubl_u8(next.val[byte[c]], here.val[byte[c]]));
                raw[c] = vcvtq_f32_s32(vmovl_s16(half == 0 ? vget_low_s16(d) : vget_high_s16(d)));
            }
            float32x4_t corrected[3] = {raw[0], raw[1], raw[2]};
            for (int k = 0; k < 3 && !identity; ++k)
                corrected[k] = vaddq_f32(vaddq_f32(vmulq_n_f32(raw[0], m(k, 0)), vmulq_n_f32(raw[1], m(k, 1))),
                                         vmulq_n_f32(raw[2], m(k, 2)));
            const float32x4_t sum = vaddq_f32(vaddq_f32(vmulq_n_f32(corrected[0], weight[0]), vmulq_n_f32(corrected[1], weight[1])),
                                              vmulq_n_f32(corrected[2], weight[2]));
            vst1q_f32(out[j].data() + 4 * half, sum);
        }
    }
#elif defined(__SSE2__)
    __m128 mm[3][3];
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) mm[k][c] = _mm_set1_ps(m(k, c));
    const __m128i zero = _mm_setzero_si128();
    for (int j = 0; j < count; ++j) {
        const int first = firsts[j];
        if (windowCut(first, width)) {
            clippedWindow(row, width, first, rgbOffset, m, weights[j], out[j].data());
            continue;
        }
        const __m128 w0 = _mm_set1_ps(weights[j][0]), w1 = _mm_set1_ps(weights[j][1]), w2 = _mm_set1_ps(weights[j][2]);
        // The 24 differences p[j + 3] - p[j], j = 3 x sample + channel, of
        // the window's pixels p = first .. first + 8, as 3 x 8 int16 lanes
        // from 16-byte loads at p, p + 3 (j = 0..15) and p + 8, p + 11 (the
        // upper halves: j = 16..23; up to byte 26, inside the row by the
        // test above), then as 6 x 4 floats: samples 0-3 from j = 0..11,
        // samples 4-7 from j = 12..23. (4 loads for the whole window, where
        // two 4-sample steps widened 4 x 12 lanes: 5 instructions fewer.)
        const std::uint8_t* p = row + 3 * first;
        auto bytes = [p](int offset) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + offset)); };
        const __m128i a = bytes(0), b = bytes(3), c = bytes(8), d = bytes(11);
        const __m128i diff[3] = {_mm_sub_epi16(_mm_unpacklo_epi8(b, zero), _mm_unpacklo_epi8(a, zero)),
                                 _mm_sub_epi16(_mm_unpackhi_epi8(b, zero), _mm_unpackhi_epi8(a, zero)),
                                 _mm_sub_epi16(_mm_unpackhi_epi8(d, zero), _mm_unpackhi_epi8(c, zero))};
        __m128 f[6];
        for (int k = 0; k < 3; ++k) {
            f[2 * k] = _mm_cvtepi32_ps(_mm_srai_epi32(_mm_unpacklo_epi16(diff[k], diff[k]), 16));
            f[2 * k + 1] = _mm_cvtepi32_ps(_mm_srai_epi32(_mm_unpackhi_epi16(diff[k], diff[k]), 16));
        }
        for (int half = 0; half < 2; ++half) {
            const __m128 d0 = f[3 * half], d1 = f[3 * half + 1], d2 = f[3 * half + 2];
            // Byte b of each pixel: j = b, b + 3, b + 6, b + 9 (j from the half's first).
            const __m128 byte0 = _mm_shuffle_ps(d0, _mm_shuffle_ps(d1, d2, _MM_SHUFFLE(0, 1, 0, 2)), _MM_SHUFFLE(2, 0, 3, 0));
            const __m128 byte1 = _mm_shuffle_ps(_mm_shuffle_ps(d0, d1, _MM_SHUFFLE(0, 0, 0, 1)),
                                                _mm_shuffle_ps(d1, d2, _MM_SHUFFLE(0, 2, 0, 3)), _MM_SHUFFLE(2, 0, 2, 0));
            const __m128 byte2 = _mm_shuffle_ps(_mm_shuffle_ps(d0, d1, _MM_SHUFFLE(0, 1, 0, 2)), d2, _MM_SHUFFLE(3, 0, 2, 0));
            const __m128 raw[3] = {bgr ? byte2 : byte0, byte1, bgr ? byte0 : byte2};
            __m128 corrected[3] = {raw[0], raw[1], raw[2]};
            for (int k = 0; k < 3 && !identity; ++k)
                corrected[k] = _mm_add_ps(_mm_add_ps(_mm_mul_ps(mm[k][0], raw[0]), _mm_mul_ps(mm[k][1], raw[1])),
                                          _mm_mul_ps(mm[k][2], raw[2]));
            const __m128 sum = _mm_add_ps(_mm_add_ps(_mm_mul_ps(w0, corrected[0]), _mm_mul_ps(w1, corrected[1])),
                                          _mm_mul_ps(w2, corrected[2]));
            _mm_storeu_ps(out[j].data() + 4 * half, sum);
        }
    }
#else
    for (int j = 0; j < count; ++j) clippedWindow(row, width, firsts[j], rgbOffset, m, weights[j], out[j].data());
#endif
}

#if defined(__x86_64__)
// The AVX2 version (x86-64-v3 and -v4 CPUs): a window's 8 samples per
// channel in one 8-lane vector, straight from the bytes by byte shuffles
// (vpshufb: SSE2 has none, hence its unpacking and 7 float shuffles per 4
// samples): 34 instructions per window, with the loop, against the SSE2
// version's 94 (780x580 under callgrind). The same floats: the differences as int32 (exact),
// then the SSE2 version's products and sums in its order.
//
// Shuffle control: per sample k < 8, byte b (the channel's) of pixel
// first + k + shift (shift 0: here, 1: next) zero-extended to int32 lane k
// (index -1 clears a byte); samples 0-3 in the low 128-bit lane, from the
// 16 bytes at pixel first, samples 4-7 in the high one, from the 16 bytes
// at byte 11 (pixel 4's byte b is their byte 1 + b). Bytes read: 0-26, the
// window's 9 pixels.
constexpr std::array<std::int8_t, 32> windowControl(int b, int shift)
{
    std::array<std::int8_t, 32> c{};
    for (int k = 0; k < 4; ++k) {
        for (int z = 1; z < 4; ++z) c[4 * k + z] = c[16 + 4 * k + z] = -1;
        c[4 * k] = static_cast<std::int8_t>(3 * (k + shift) + b);
        c[16 + 4 * k] = static_cast<std::int8_t>(1 + 3 * (k + shift) + b);
    }
    return c;
}

template <bool bgr, bool identity>
[[gnu::target("arch=x86-64-v3")]] void windowsAvx2(const std::uint8_t* row, int width, const std::int32_t* firsts,
                                                   const cv::Vec3f* weights, int count,
                                                   const std::array<int, 3>& rgbOffset, const cv::Matx33f& m,
                                                   std::array<float, kWindowSamples + 1>* out)
{
    constexpr int byte[3] = {bgr ? 2 : 0, 1, bgr ? 0 : 2};  // of R, G, B in a pixel
    static constexpr std::array<std::array<std::int8_t, 32>, 6> kControls = {
        windowControl(byte[0], 0), windowControl(byte[0], 1), windowControl(byte[1], 0),
        windowControl(byte[1], 1), windowControl(byte[2], 0), windowControl(byte[2], 1)};
    __m256i controls[6];
    for (int i = 0; i < 6; ++i) controls[i] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kControls[i].data()));
    __m256 mm[3][3];
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) mm[k][c] = _mm256_set1_ps(m(k, c));
    for (int j = 0; j < count; ++j) {
        const int first = firsts[j];
        if (windowCut(first, width)) {
            clippedWindow(row, width, first, rgbOffset, m, weights[j], out[j].data());
            continue;
        }
        const std::uint8_t* p = row + 3 * first;
        const __m256i bytes =
            _mm256_inserti128_si256(_mm256_castsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))),
                                    _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 11)), 1);
        __m256 raw[3];
        for (int c = 0; c < 3; ++c)
            raw[c] = _mm256_cvtepi32_ps(_mm256_sub_epi32(_mm256_shuffle_epi8(bytes, controls[2 * c + 1]),
                                                         _mm256_shuffle_epi8(bytes, controls[2 * c])));
        __m256 corrected[3] = {raw[0], raw[1], raw[2]};
        for (int k = 0; k < 3 && !identity; ++k)
            corrected[k] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(mm[k][0], raw[0]), _mm256_mul_ps(mm[k][1], raw[1])),
                                         _mm256_mul_ps(mm[k][2], raw[2]));
        const cv::Vec3f& weight = weights[j];
        const __m256 sum = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_broadcast_ss(&weight[0]), corrected[0]),
                                                       _mm256_mul_ps(_mm256_broadcast_ss(&weight[1]), corrected[1])),
                                         _mm256_mul_ps(_mm256_broadcast_ss(&weight[2]), corrected[2]));
        _mm256_storeu_ps(out[j].data(), sum);
    }
}

#endif

// Calls run(bgr, identity) with the two as std::true_type / std::false_type,
// so a kernel template takes them at compile time.
template <typename Run>
void withLayout(bool bgr, bool identity, Run run)
{
    using Yes = std::true_type;
    using No = std::false_type;
    if (bgr)
        identity ? run(Yes{}, Yes{}) : run(Yes{}, No{});
    else
        identity ? run(No{}, Yes{}) : run(No{}, No{});
}

// The kernel for the channel order and whether there is crosstalk.
void windowsFor(bool bgr, bool identity, const std::uint8_t* row, int width, const std::int32_t* firsts,
                const cv::Vec3f* weights, int count, const std::array<int, 3>& rgbOffset, const cv::Matx33f& m,
                std::array<float, kWindowSamples + 1>* out)
{
    withLayout(bgr, identity, [&](auto b, auto i) {
        windows<decltype(b)::value, decltype(i)::value>(row, width, firsts, weights, count, rgbOffset, m, out);
    });
}

#if defined(__x86_64__)
void windowsAvx2For(bool bgr, bool identity, const std::uint8_t* row, int width, const std::int32_t* firsts,
                    const cv::Vec3f* weights, int count, const std::array<int, 3>& rgbOffset, const cv::Matx33f& m,
                    std::array<float, kWindowSamples + 1>* out)
{
    withLayout(bgr, identity, [&](auto b, auto i) {
        windowsAvx2<decltype(b)::value, decltype(i)::value>(row, width, firsts, weights, count, rgbOffset, m, out);
    });
}

// The version per CPU, picked at run time by GCC's function multiversioning
// (an ifunc; target_clones cannot give its clones different bodies).
[[gnu::target("default")]] void windowsVersion(bool bgr, bool identity, const std::uint8_t* row, int width,
                                               const std::int32_t* firsts, const cv::Vec3f* weights, int count,
                                               const std::array<int, 3>& rgbOffset, const cv::Matx33f& m,
                                               std::array<float, kWindowSamples + 1>* out)
{
    windowsFor(bgr, identity, row, width, firsts, weights, count, rgbOffset, m, out);
}
[[gnu::target("arch=x86-64-v3")]] void windowsVersion(bool bgr, bool identity, const std::uint8_t* row, int width,
                                                      const std::int32_t* firsts, const cv::Vec3f* weights, int count,
                                                      const std::array<int, 3>& rgbOffset, const cv::Matx33f& m,
                                                      std::array<float, kWindowSamples + 1>* out)
{
    windowsAvx2For(bgr, identity, row, width, firsts, weights, count, rgbOffset, m, out);
}
[[gnu::target("arch=x86-64-v4")]] void windowsVersion(bool bgr, bool identity, const std::uint8_t* row, int width,
                                                      const std::int32_t* firsts, const cv::Vec3f* weights, int count,
                                                      const std::array<int, 3>& rgbOffset, const cv::Matx33f& m,
                                                      std::array<float, kWindowSamples + 1>* out)
{
    windowsAvx2For(bgr, identity, row, width, firsts, weights, count, rgbOffset, m, out);
}
#endif

}  // namespace

void projectedGradientWindows(const std::uint8_t* row, int width, const std::int32_t* firsts,
                              const cv::Vec3f* weights, int count, const std::array<int, 3>& rgbOffset,
                              const cv::Matx33f& m, std::array<float, kWindowSamples + 1>* out)
{
    const bool bgr = rgbOffset == std::array<int, 3>{2, 1, 0}, identity = m == cv::Matx33f::eye();
    if (bgr || rgbOffset == std::array<int, 3>{0, 1, 2}) {
#if defined(__x86_64__)
        windowsVersion(bgr, identity, row, width, firsts, weights, count, rgbOffset, m, out);
#else
        windowsFor(bgr, identity, row, width, firsts, weights, count, rgbOffset, m, out);
#endif
    } else
        for (int j = 0; j < count; ++j) clippedWindow(row, width, firsts[j], rgbOffset, m, weights[j], out[j].data());
}

}  // namespace stria::pipeline
