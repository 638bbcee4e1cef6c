#pragma once
// symbolError (eq. 5-7 after removing a texture's common change, edges.cpp)
// for the traversal, inline: it tests ~14 000 symbols per 780x580 decode
// (findUniquePath, bestHypothesis, weighEvidence), and a call cost ~19
// instructions of the ~65 (arguments, return, the constants and the table's
// address, which the traversal's loops keep in registers): 780x580 traversal
// 11.35 -> 11.08 M instructions per decode. edges.cpp has the EqualizedChange
// form and the edge stage's lanes, tests/decoder/test_kernels.cpp the
// per-channel reference.

#include "pipeline/decoder/simd.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__aarch64__)
#include <arm_neon.h>
#endif

namespace stria::pipeline {
namespace symbol_error {

using Lanes = Float4;
using LaneMask = std::int32_t __attribute__((vector_size(16)));

[[gnu::always_inline]] inline Lanes lanesOf(float v) { return Lanes{v, v, v, v}; }
[[gnu::always_inline]] inline Lanes absolute(Lanes v) { return (Lanes)((LaneMask)v & 0x7fffffff); }
[[gnu::always_inline]] inline Lanes squareRoot(Lanes v)
{
#if defined(__SSE2__)
    return _mm_sqrt_ps(v);
#elif defined(__aarch64__)
    return vsqrtq_f32(v);
#else
    for (int i = 0; i < 4; ++i) v[i] = std::sqrt(v[i]);
    return v;
#endif
}

using LaneIndex = std::int32_t __attribute__((vector_size(16)));

// a > b ? a : b and a < b ? a : b per lane, as maxps and minps on x86-64
// (GCC makes the ternary forms a compare and three logic operations where an
// operand is a constant).
[[gnu::always_inline]] inline Lanes maximumOf(Lanes a, Lanes b)
{
#if defined(__SSE2__)
    return _mm_max_ps(a, b);
#else
    return a > b ? a : b;
#endif
}
[[gnu::always_inline]] inline Lanes minimumOf(Lanes a, Lanes b)
{
#if defined(__SSE2__)
    return _mm_min_ps(a, b);
#else
    return a < b ? a : b;
#endif
}

// symbolError's per-symbol constants, so that a test reads its channels and
// factors from a table instead of building them by selects (a loop over the
// channels per group, then scalar sums and maxima of the lanes: ~120
// instructions per test, ~60 now). The same IEEE operations on the same
// values, in the same order, as the group sums of the per-channel reference
// (test_kernels.cpp), as one formula for every symbol:
//   ((c[p0] + c[p1] * p1Weight) * pScale + (c[q0] + c[q1] * q1Weight) * qScale) * scale
// where the weights and scales are 1, 0.5 or 0, exactly: a group of one
// channel is c[p0] + c[p0] * 0 (= c[p0]), one of two c[p0] + c[p1] (the sum
// in channel order); the constant channels' mean is P * pScale (+ Q * 0), the
// midpoint of the falling and the rising ones (F * fs + R * rs) * 0.5; the
// null symbol's mean is (c0 + c1) + c2, divided by 3 afterwards. x + +-0 is x
// up to the sign of a zero, which the match does not see (c - common then
// differs in zeros' signs only, and the errors are squared).
struct alignas(16) SymbolMatch {
    // Eq. 5-6 per channel from the corrected change x:
    // (((x ^ flip) & keep) + add) * scale is |x| * off for a constant channel
    // (keep clears the sign bit, add 0) and (1 - sign * x) * on for a moving
    // one (flip negates a rising channel's x, add 1: 1 + -x is 1 - x); lane
    // 3 gives 0 (MatchScales::channel: the scales).
    LaneMask flip, keep;
    Lanes add;
    std::uint8_t p0, p1, q0, q1;
    float p1Weight, pScale, q1Weight, qScale, scale;
};

inline constexpr auto kSymbolMatch = [] {
    std::array<SymbolMatch, kSymbolCount> match{};
    for (int s = 0; s < kSymbolCount; ++s) {
        const std::array<std::int8_t, 3>& sign = kSymbolSigns[s];
        SymbolMatch& m = match[s];
        std::array<std::array<std::uint8_t, 3>, 3> members{};  // per group (falling, constant, rising): its channels
        std::array<int, 3> count{};
        for (int c = 0; c < 3; ++c) {
            const int group = sign[c] + 1;
            members[group][count[group]++] = static_cast<std::uint8_t>(c);
        }
        auto flip = [&](int c) { return sign[c] > 0 ? std::numeric_limits<std::int32_t>::min() : 0; };
        auto keep = [&](int c) { return sign[c] == 0 ? 0x7fffffff : -1; };
        auto add = [&](int c) { return sign[c] == 0 ? 0.0f : 1.0f; };
        m.flip = LaneMask{flip(0), flip(1), flip(2), 0};
        m.keep = LaneMask{keep(0), keep(1), keep(2), 0};
        m.add = Lanes{add(0), add(1), add(2), 0};
        // P (or Q) from a group's channels: one (the second the same, weight 0) or two.
        auto groupSum = [&](int group, std::uint8_t& first, std::uint8_t& second, float& weight) {
            first = members[group][0];
            second = count[group] > 1 ? members[group][1] : members[group][0];
            weight = count[group] > 1 ? 1.0f : 0.0f;
        };
        auto groupScale = [&](int group) { return count[group] == 2 ? 0.5f : 1.0f; };
        if (count[1] == 3) {  // the null symbol: (c0 + c1) + c2, divided by 3 by symbolError
            m.p0 = 0, m.p1 = 1, m.q0 = m.q1 = 2;
            m.p1Weight = m.pScale = m.qScale = m.scale = 1.0f;
        } else if (count[1] > 0) {  // the constant channels' mean
            groupSum(1, m.p0, m.p1, m.p1Weight);
            m.pScale = groupScale(1);
            m.scale = 1.0f;
        } else if (count[0] > 0 && count[2] > 0) {  // the midpoint of the falling and the rising ones
            groupSum(0, m.p0, m.p1, m.p1Weight);
            m.pScale = groupScale(0);
            groupSum(2, m.q0, m.q1, m.q1Weight);
            m.qScale = groupScale(2);
            m.scale = 0.5f;
        }  // else every channel moves the same way: no common change (all factors 0)
    }
    return match;
}();

// change: c[0..2] and a fourth float, finite, the lanes of c (lane 3
// ignored). c is normalised (equalizedChange): its largest |c| is 1, or
// every channel is 0 (relative 0, bound 0).
[[gnu::always_inline]] inline float symbolErrorLanes(const float* change, Lanes c, Lanes bound, SymbolCode symbol,
                                                const MatchScales& scales)
{
    const SymbolMatch& m = kSymbolMatch[symbol];
    // The common change (see SymbolMatch), held within +-bound:
    // std::clamp(common, -bound, bound) (bound >= 0) as std::min(bound,
    // common) and std::max(-bound, ..), in the reference's operand order.
    float common = ((change[m.p0] + change[m.p1] * m.p1Weight) * m.pScale +
                    (change[m.q0] + change[m.q1] * m.q1Weight) * m.qScale) *
                   m.scale;
    if (symbol == kNullSymbol) [[unlikely]]
        common /= 3;
    const Lanes clamped = maximumOf(-bound, minimumOf(bound, lanesOf(common)));
    // The corrected change normalised again: divided by its largest |x|,
    // which is at least 0.7 where relative > 0 (a channel of c is +-1,
    // |common| <= 0.3) and 0 where it is 0 (c and common 0): the reference
    // divides by 1 if the common change or that maximum is 0, which leaves x
    // as it is in both cases (c has a channel +-1, so the maximum is 1; x is
    // +-0), as does the division by max(maximum, 0.5).
    const Lanes corrected = c - clamped;
    const Lanes size = absolute(corrected);
    const Lanes largest = maximumOf(maximumOf(size, __builtin_shuffle(size, LaneIndex{1, 2, 0, 3})),
                                    __builtin_shuffle(size, LaneIndex{2, 0, 1, 3}));
    const Lanes x = corrected / maximumOf(largest, lanesOf(0.5f));
    Lanes scale;
    std::memcpy(&scale, scales.channel[symbol].data(), sizeof scale);
    const Lanes e = ((Lanes)(((LaneMask)x ^ m.flip) & m.keep) + m.add) * scale;
    const Lanes square = e * e;
    // (square[0] + square[1]) + square[2] in lane 0, and its root.
    const Lanes sum = square + __builtin_shuffle(square, LaneIndex{1, 1, 1, 1}) + __builtin_shuffle(square, LaneIndex{2, 2, 2, 2});
    return squareRoot(sum)[0];
}

}  // namespace symbol_error

// symbolError(equalizedChange(ws, from, to), symbol, scales) for the edge
// whose change from a to b is `change`, given symbolFromA = symbol if from
// is a, else reversedSymbol(symbol): the same float (from b the change is
// the negated one, up to the sign of zeros, which symbolError does not see,
// and the reversed symbol's arithmetic on it is negated step for step).
[[gnu::always_inline]] inline float symbolError(const EdgeChange& change, SymbolCode symbolFromA, const MatchScales& scales)
{
    using namespace symbol_error;
    static_assert(offsetof(EdgeChange, c) == 0 && offsetof(EdgeChange, commonBound) == 12 && sizeof(EdgeChange) == sizeof(Lanes));
    Lanes c;  // lane 3: commonBound
    std::memcpy(&c, change.c.data(), sizeof c);
    return symbolErrorLanes(change.c.data(), c, __builtin_shuffle(c, LaneIndex{3, 3, 3, 3}), symbolFromA, scales);
}

}  // namespace stria::pipeline
