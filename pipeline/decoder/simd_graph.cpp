// Region graph kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd_graph.hpp"

#include <cmath>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace stria::pipeline {

std::uint64_t borderMaskReference(const std::int32_t* a, const std::int32_t* b, int count)
{
    std::uint64_t bits = 0;
    for (int i = 0; i < count; ++i)
        if (a[i] != b[i]) bits |= std::uint64_t{1} << i;
    return bits;
}

std::uint64_t borderMask(const std::int32_t* a, const std::int32_t* b, int count)
{
    // 16 labels per step, no branch per pixel (a border every ~6 pixels is
    // unpredictable); the caller walks the set bits. A whole word (most
    // calls) in four steps with constant shifts; a shorter one in steps and
    // a last step of the 16 labels ending at count, which overlaps the step
    // before (the same bits again) instead of a label by label tail.
    // 32-bit ARM (armv7-a NEON) has none of uzp1, addv and byteMask64's
    // AArch64 instructions: it takes the label by label loop.
#if defined(__aarch64__) || defined(__SSE2__)
#if defined(__aarch64__)
    const uint8x16_t weights = {1, 2, 4, 8, 16, 32, 64, 128, 1, 2, 4, 8, 16, 32, 64, 128};
    // 16 labels' comparisons as bytes (0xff: equal): the low bytes of the
    // 32-bit masks gathered by three uzp1 (even elements), in order (the
    // narrowing moves took 6 instructions).
    auto equal16 = [&](int at) {
        auto equal4 = [&](int i) { return vreinterpretq_u16_u32(vceqq_s32(vld1q_s32(a + i), vld1q_s32(b + i))); };
        const uint16x8_t low = vuzp1q_u16(equal4(at), equal4(at + 4));
        const uint16x8_t high = vuzp1q_u16(equal4(at + 8), equal4(at + 12));
        return vuzp1q_u8(vreinterpretq_u8_u16(low), vreinterpretq_u8_u16(high));
    };
    auto differ16 = [&](int at) -> std::uint64_t {
        const uint8x16_t differ = vbicq_u8(weights, equal16(at));
        return vaddv_u8(vget_low_u8(differ)) | static_cast<unsigned>(vaddv_u8(vget_high_u8(differ))) << 8;
    };
    // A whole word by byteMask64 (simd.hpp) of the 64 labels' differences.
    auto differ64 = [&]() -> std::uint64_t {
        return byteMask64(vmvnq_u8(equal16(0)), vmvnq_u8(equal16(16)), vmvnq_u8(equal16(32)), vmvnq_u8(equal16(48)));
    };
#else
    auto equal4 = [&](int at) {
        return _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + at)),
                               _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + at)));
    };
    auto differ16 = [&](int at) -> std::uint64_t {
        // Saturating packs keep the all-ones / zero lanes.
        const __m128i equal = _mm_packs_epi16(_mm_packs_epi32(equal4(at), equal4(at + 4)),
                                              _mm_packs_epi32(equal4(at + 8), equal4(at + 12)));
        return static_cast<unsigned>(~_mm_movemask_epi8(equal) & 0xffff);
    };
#endif
#if defined(__aarch64__)
    if (count == 64) return differ64();
#else
    if (count == 64) return differ16(0) | differ16(16) << 16 | differ16(32) << 32 | differ16(48) << 48;
#endif
    if (count >= 16) {
        std::uint64_t bits = 0;
        int i = 0;
        for (; i + 16 <= count; i += 16) bits |= differ16(i) << i;
        if (i < count) bits |= differ16(count - 16) << (count - 16);
        return bits;
    }
#endif
    std::uint64_t bits = 0;
    for (int i = 0; i < count; ++i) bits |= std::uint64_t{a[i] != b[i]} << i;
    return bits;
}

PairGradient horizontalPairGradient(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int x,
                                    const cv::Vec2f& primary)
{
    return graph_kernels::horizontalPair(up, row, down, x, graph_kernels::plainWeights(primary));
}

PairGradient verticalPairGradient(const std::uint8_t* row, const std::uint8_t* below, int x, const cv::Vec2f& primary)
{
    return graph_kernels::verticalPair(row, below, x, graph_kernels::plainWeights(primary));
}

}  // namespace stria::pipeline
