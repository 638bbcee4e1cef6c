// Stage 7: 3D points (section 5 of the paper).
//
// Along every image row, each pair of neighbouring pixels whose regions were
// decoded as consecutive stripes k, k+1 marks stripe edge k. The edge is
// located with sub-pixel precision as the peak of the colour gradient along
// the row: the gradient is projected onto the edge's expected symbol (each
// channel divided by the regions' range, eq. 1), so texture that changes other
// channels does not pull the peak. The strongest half-pixel difference within
// +-2 px of the region border is the peak; the centroid of the differences
// around it (above a quarter of its height) is the edge position. On the
// tilted plane this halves the depth noise of a 3-point parabola (0.19 mm
// against 0.33 mm std at noise 2; docs/algorithm.md).
// The point is where the camera ray through (u, row) meets edge k's light plane.
// One point per edge and row: the projector's light plane k meets a row's
// epipolar plane in a single ray, which lights only the first surface it
// hits; of two points of edge k in a row, the farther lies in the nearer's
// shadow and is dropped (a stripe decoded across a depth step with the
// offset of the background's sequence; docs/algorithm.md section 7).
#include "pipeline/decoder/simd.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__ARM_NEON)
#include <arm_neon.h>
#endif
#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace stria::pipeline {
namespace {

constexpr int kSearchRadius = 2;
constexpr float kCentroidThreshold = 0.25f;
// The stripe of an undecoded region in computePoints' compact copy: more
// than 1 away from every stripe and from itself minus any stripe.
constexpr std::int32_t kUndecoded = -(1 << 30);

// Four float lanes (GCC vector extensions: SSE2 on x86-64, NEON on ARM).
using Lanes = float __attribute__((vector_size(16)));

// Per symbol code and orientation (0: the stripe index falls from left to
// right, 1: it rises), the numerators of an edge's channel weights: the
// orientation (-1 or +1) times the symbol's expected sign, the same float
// products step 2 took per edge (its int-to-float conversions and products
// were 4 of the 9 instructions per channel). In lanes 0-2 of a vector (lane
// 3 is 0), as step 2 divides them.
constexpr auto kSignedSigns = [] {
    std::array<std::array<std::array<float, 4>, 2>, kSymbolCount> numerators{};
    for (int s = 0; s < kSymbolCount; ++s)
        for (int o = 0; o < 2; ++o)
            for (int c = 0; c < 3; ++c)
                numerators[s][o][c] = (o == 1 ? 1.0f : -1.0f) * static_cast<float>(kSymbolSigns[s][c]);
    return numerators;
}();
// Two double lanes (SSE2 / NEON), and two ints.
using Doubles = double __attribute__((vector_size(16)));
using Pair = std::int32_t __attribute__((vector_size(8)));
// Four int lanes (comparison masks of Lanes), two long ones (of Doubles).
using Ints = std::int32_t __attribute__((vector_size(16)));
using Longs = std::int64_t __attribute__((vector_size(16)));
// Four double lanes and four long ones (AVX, in x86-64-v3 code only).
using Doubles4 = double __attribute__((vector_size(32)));
using Longs4 = std::int64_t __attribute__((vector_size(32)));

// Four records of 4 doubles to 4 fields of 4 lanes: v[j][i] = v[i][j] before.
[[gnu::always_inline]] inline void transposeDoubles(Doubles4 v[4])
{
    const Longs4 low{0, 4, 2, 6}, high{1, 5, 3, 7};
    const Doubles4 t0 = __builtin_shuffle(v[0], v[1], low), t1 = __builtin_shuffle(v[0], v[1], high);
    const Doubles4 t2 = __builtin_shuffle(v[2], v[3], low), t3 = __builtin_shuffle(v[2], v[3], high);
    v[0] = __builtin_shuffle(t0, t2, Longs4{0, 1, 4, 5});
    v[1] = __builtin_shuffle(t1, t3, Longs4{0, 1, 4, 5});
    v[2] = __builtin_shuffle(t0, t2, Longs4{2, 3, 6, 7});
    v[3] = __builtin_shuffle(t1, t3, Longs4{2, 3, 6, 7});
}

// Grid points a[0], a[1] and b[0], b[1] (the two lanes' cell corners in one
// grid row), widened exactly to double: out = x of [0], y of [0], x of [1],
// y of [1], each with a in lane 0 and b in lane 1. On SSE2 from two 16-byte
// loads and shuffles (14 instructions): GCC builds the generic form from
// 8 scalar loads and conversions (40).
void cellCorners(const cv::Vec2f* a, const cv::Vec2f* b, Doubles out[4])
{
#if defined(__SSE2__)
    const __m128 pa = _mm_loadu_ps(&a[0][0]), pb = _mm_loadu_ps(&b[0][0]);
    const __m128 first = _mm_unpacklo_ps(pa, pb), second = _mm_unpackhi_ps(pa, pb);
    out[0] = _mm_cvtps_pd(first);
    out[1] = _mm_cvtps_pd(_mm_movehl_ps(first, first));
    out[2] = _mm_cvtps_pd(second);
    out[3] = _mm_cvtps_pd(_mm_movehl_ps(second, second));
#elif defined(__aarch64__)
    // The same on NEON: two loads, two zips and four widenings.
    const float32x4_t pa = vld1q_f32(&a[0][0]), pb = vld1q_f32(&b[0][0]);
    const float32x4_t first = vzip1q_f32(pa, pb), second = vzip2q_f32(pa, pb);
    out[0] = vcvt_f64_f32(vget_low_f32(first));
    out[1] = vcvt_high_f64_f32(first);
    out[2] = vcvt_f64_f32(vget_low_f32(second));
    out[3] = vcvt_high_f64_f32(second);
#else
    for (int k = 0; k < 2; ++k)
        for (int c = 0; c < 2; ++c) out[2 * k + c] = Doubles{a[k][c], b[k][c]};
#endif
}

// Camera rays along one image row: a bilinear look-up in the undistorted ray
// grid (rayGrid, every rayGridStep pixels), with the row's grid row and
// vertical weight computed once per row, and u divided by the grid step as a
// product with its inverse, exact for a power-of-two step (the same rays, bit
// for bit, as dividing per point did).
class RowRays {
public:
    RowRays(const DecoderWorkspace& ws, int y)
        : gridStep_(ws.rayGridStep), inverseStep_(1.0 / ws.rayGridStep),
          exactInverse_((ws.rayGridStep & (ws.rayGridStep - 1)) == 0), gridWidth_(ws.rayGridWidth)
    {
        const double gy = std::clamp(static_cast<double>(y) / gridStep_, 0.0, ws.rayGridHeight - 1.000001);
        const int y0 = static_cast<int>(gy);
        fy_ = gy - y0;
        gridRow_ = ws.rayGrid.get() + y0 * ws.rayGridWidth;
    }

    // The rays through (u[0], y) and (u[1], y), one per double lane (half
    // the instructions of one point at a time): xn and yn get their x and y
    // (z is 1). Per lane, std::min(std::max(gx, 0.0), last) and cv::Vec2d's
    // bilinear sums in their order: the rays of the scalar form, bit for bit.
    void at(Doubles u, Doubles& xn, Doubles& yn) const
    {
        const Doubles zero{}, last = zero + (gridWidth_ - 1.000001);
        Doubles gx = exactInverse_ ? u * inverseStep_ : u / gridStep_;
        gx = gx < zero ? zero : gx;  // std::max(gx, 0.0)
        gx = last < gx ? last : gx;  // std::min(gx, last)
#if defined(__aarch64__)
        // arm64: both lanes converted in one fcvtzs and back in one scvtf, in
        // 64-bit lanes (GCC converted the Pair lane by lane in scalar
        // registers, 6 instructions); gx >= 0 and below the grid's width:
        // the same integers (truncated) and the same fx.
        const int64x2_t x0 = vcvtq_s64_f64(gx);
        const Doubles fx = gx - Doubles(vcvtq_f64_s64(x0));
        // The cells' byte offsets by one vector shift (a q load takes no
        // index scaled by 8: GCC shifted and added per lane, 6 instructions).
        static_assert(sizeof(cv::Vec2f) == 8);
        const int64x2_t offset = vshlq_n_s64(x0, 3);
        const auto* top0 = reinterpret_cast<const char*>(gridRow_);
        const char* bottom0 = top0 + static_cast<std::ptrdiff_t>(gridWidth_) * sizeof(cv::Vec2f);
        const auto cell = [](const char* base, std::int64_t at) {
            return reinterpret_cast<const cv::Vec2f*>(base + at);
        };
        Doubles top[4], bottom[4];
        cellCorners(cell(top0, offset[0]), cell(top0, offset[1]), top);
        cellCorners(cell(bottom0, offset[0]), cell(bottom0, offset[1]), bottom);
#else
        const Pair x0 = __builtin_convertvector(gx, Pair);
        const Doubles fx = gx - __builtin_convertvector(x0, Doubles);
        Doubles top[4], bottom[4];
        cellCorners(gridRow_ + x0[0], gridRow_ + x0[1], top);
        cellCorners(gridRow_ + x0[0] + gridWidth_, gridRow_ + x0[1] + gridWidth_, bottom);
#endif
        const Doubles topX = top[0] * (1 - fx) + top[2] * fx;
        const Doubles topY = top[1] * (1 - fx) + top[3] * fx;
        const Doubles bottomX = bottom[0] * (1 - fx) + bottom[2] * fx;
        const Doubles bottomY = bottom[1] * (1 - fx) + bottom[3] * fx;
        xn = topX * (1 - fy_) + bottomX * fy_;
        yn = topY * (1 - fy_) + bottomY * fy_;
    }

#if defined(__x86_64__)
    // The same for 4 lanes (AVX), bit for bit: a lane's cell corners (x, y
    // of columns x0, x0 + 1: 4 floats) widened to 4 doubles by one
    // vcvtps2pd, the 4 lanes' then transposed to 4 fields (GCC 12 widened a
    // vector of 4 floats or ints to doubles in halves, through the stack).
    [[gnu::target("arch=x86-64-v3"), gnu::always_inline]] void at4(const Doubles4& u, Doubles4& xn, Doubles4& yn) const
    {
        const Doubles4 zero{}, last = zero + (gridWidth_ - 1.000001);
        Doubles4 gx = exactInverse_ ? u * inverseStep_ : u / gridStep_;
        gx = gx < zero ? zero : gx;  // std::max(gx, 0.0)
        gx = last < gx ? last : gx;  // std::min(gx, last)
        const __m128i x0 = _mm256_cvttpd_epi32(__m256d(gx));
        const Doubles4 fx = gx - Doubles4(_mm256_cvtepi32_pd(x0));
        Doubles4 top[4], bottom[4];
        for (int i = 0; i < 4; ++i) {
            const float* cell = &gridRow_[Ints(x0)[i]][0];
            top[i] = Doubles4(_mm256_cvtps_pd(_mm_loadu_ps(cell)));
            bottom[i] = Doubles4(_mm256_cvtps_pd(_mm_loadu_ps(cell + 2 * gridWidth_)));
        }
        transposeDoubles(top);
        transposeDoubles(bottom);
        const Doubles4 topX = top[0] * (1 - fx) + top[2] * fx;
        const Doubles4 topY = top[1] * (1 - fx) + top[3] * fx;
        const Doubles4 bottomX = bottom[0] * (1 - fx) + bottom[2] * fx;
        const Doubles4 bottomY = bottom[1] * (1 - fx) + bottom[3] * fx;
        xn = topX * (1 - fy_) + bottomX * fy_;
        yn = topY * (1 - fy_) + bottomY * fy_;
    }
#endif

private:
    int gridStep_;
    double inverseStep_;
    bool exactInverse_;
    int gridWidth_;
    double fy_ = 0;
    const cv::Vec2f* gridRow_ = nullptr;
};


// Bit i set where lane i of a comparison mask is (all ones, else 0).
int laneBits(Ints mask)
{
#if defined(__SSE2__)
    return _mm_movemask_ps(_mm_castsi128_ps(__m128i(mask)));
#elif defined(__aarch64__)
    const uint32x4_t bit = {1, 2, 4, 8};
    return static_cast<int>(vaddvq_u32(vandq_u32(vreinterpretq_u32_s32(mask), bit)));
#else
    int bits = 0;
    for (int i = 0; i < 4; ++i) bits |= (mask[i] & 1) << i;
    return bits;
#endif
}

// Step 5 of computePoints for one batch of a row's edges: the point where
// the camera ray through (u, y) meets the edge's light plane
// (RigModel::intersectRay's arithmetic and tests), two edges per double lanes
// (one division for two points), then the points kept, one per edge and row,
// written straight to the output (through a staging array, each point was
// stored and copied: 0.26 M instructions per 780x580 decode). Edge j at
// columns[j] (u), its pattern edge edges[j], located if locatedMasks[j]
// (all ones, else 0); rowPoint as in computePoints. False if the output is
// full (ws.truncated set: the frame is cut there).
[[gnu::always_inline]] inline bool pointsOfBatchPairs(DecoderWorkspace& ws, const RowRays& rays, const double* columns,
                                                      const std::int32_t* edges, const std::int64_t* locatedMasks,
                                                      int batch, float rowV, std::int32_t* rowPoint)
{
    const Plane* planes = ws.lightPlanes.get();
    // The count and the output in locals: through ws, GCC
    // reloaded them after every point's store.
    ScanPoint* const points = ws.points;
    int pointCount = ws.pointCount;
    const int maxPoints = ws.maxPoints;
    for (int j = 0; j < batch; j += 2) {
        Doubles xn, yn, u;
        std::memcpy(&u, &columns[j], sizeof u);
        rays.at(u, xn, yn);
        const Plane &p0 = planes[edges[j]], &p1 = planes[edges[j + 1]];
        // intersectRay's dot product starts from s = 0: (0 + a) + b
        // differs from a + b only in a zero's sign, when the sum
        // is zero, which is rejected either way; the z term is n[2] * 1.
#if defined(__aarch64__)
        // arm64: the two planes' 4 fields in lanes by two structure loads
        // (ld4r of p0's to both lanes, ld4 of p1's to lane 1), where GCC
        // inserted the 8 doubles one by one (14 instructions). The same
        // values, so the same arithmetic as below (-p.d as the negated lanes).
        static_assert(sizeof(Plane) == 4 * sizeof(double) && offsetof(Plane, d) == 3 * sizeof(double));
        const float64x2x4_t plane = vld4q_lane_f64(&p1.normal[0], vld4q_dup_f64(&p0.normal[0]), 1);
        const Doubles denom = Doubles(plane.val[0]) * xn + Doubles(plane.val[1]) * yn + Doubles(plane.val[2]);
        const Doubles t = -Doubles(plane.val[3]) / denom;
#else
        const Doubles denom = Doubles{p0.normal[0], p1.normal[0]} * xn +
                              Doubles{p0.normal[1], p1.normal[1]} * yn + Doubles{p0.normal[2], p1.normal[2]};
        const Doubles t = Doubles{-p0.d, -p1.d} / denom;
#endif
        // Not parallel (|denom| >= 1e-12) and in front of the camera:
        // then t's bits (t > 0: not all zero), else +0's (all
        // zero). GCC 12 stores a comparison mask as such lane by
        // lane through scalar registers (and 1, neg); a select of
        // t is one andpd. (|denom| >= 1e-12 as two tests, not as
        // ~(denom < 1e-12 & denom > -1e-12): they differ only for
        // a NaN denom, whose t is NaN and fails t > 0.)
#if defined(__aarch64__)
        // arm64: |denom| >= 1e-12 as vcageq (GCC: fabs, fcmge; 2 instructions
        // where the two compares and the or took 3), also false for a NaN.
        const Doubles valid = (t > Doubles{}) & Longs(vcageq_f64(denom, vdupq_n_f64(1e-12))) ? t : Doubles{};
#else
        const Doubles valid = (t > Doubles{}) & ((denom >= 1e-12) | (denom <= -1e-12)) ? t : Doubles{};
#endif
        // Only edges located in step 4 (a mask of t's bits: GCC
        // scalarised a mask of the comparisons' masks).
        Longs located;
        std::memcpy(&located, &locatedMasks[j], sizeof located);
        const Longs kept = std::bit_cast<Longs>(valid) & located;
        const Doubles px = xn * t, py = yn * t;
        for (int i = 0; i < 2 && j + i < batch; ++i) {
            if (!kept[i]) continue;
            const int edge = edges[j + i];
            const ScanPoint scanPoint{
                cv::Vec3f(static_cast<float>(px[i]), static_cast<float>(py[i]), static_cast<float>(t[i])),
                cv::Point2f(static_cast<float>(columns[j + i]), rowV), edge};
            // Along one projector ray the camera depth grows with the
            // distance from the projector: the smaller z is the lit point.
            if (const int earlier = rowPoint[edge]; earlier >= 0) {
                if (scanPoint.position[2] < points[earlier].position[2]) points[earlier] = scanPoint;
                continue;
            }
            if (pointCount == maxPoints) {
                ws.pointCount = pointCount;
                ws.truncated = true;  // the frame is cut here
                return false;
            }
            rowPoint[edge] = pointCount;
            points[pointCount++] = scanPoint;
        }
    }
    ws.pointCount = pointCount;
    return true;
}

#if defined(__x86_64__)
// Step 5 for 4 edges at a time in 256-bit vectors (x86-64-v3 and -v4 CPUs):
// pointsOfBatchPairs' arithmetic, per lane the same operations in the same
// order, so the same floats and points; half its vector instructions, and
// the grid cells, light planes and points moved by 4 x 4 transposes rather
// than lane by lane (780x580: 72 -> 48 instructions per edge).
[[gnu::target("arch=x86-64-v3")]] bool pointsOfBatchQuads(DecoderWorkspace& ws, const RowRays& rays,
                                                          const double* columns, const std::int32_t* edges,
                                                          const std::int64_t* locatedMasks, int batch, float rowV,
                                                          std::int32_t* rowPoint)
{
    static_assert(sizeof(Plane) == 4 * sizeof(double) && offsetof(Plane, d) == 3 * sizeof(double));
    static_assert(offsetof(ScanPoint, pixel) == 3 * sizeof(float) && offsetof(ScanPoint, edge) == 5 * sizeof(float));
    const Plane* planes = ws.lightPlanes.get();
    ScanPoint* const points = ws.points;
    int pointCount = ws.pointCount;
    const int maxPoints = ws.maxPoints;
    // A copy of the rays: through the reference, GCC reloaded their fields
    // (and recomputed what they give) after every point's store.
    const RowRays rowRays = rays;
    ScanPoint* next = points + pointCount;  // points[pointCount] (as a pointer: no index arithmetic per point)
    for (int j = 0; j < batch; j += 4) {  // lanes past the batch (the arrays have room) not located
        Doubles4 u, xn, yn;
        std::memcpy(&u, &columns[j], sizeof u);
        rowRays.at4(u, xn, yn);
        Doubles4 plane[4];  // normal[0], normal[1], normal[2] and d of each lane's edge
        for (int i = 0; i < 4; ++i) plane[i] = Doubles4(_mm256_loadu_pd(&planes[edges[j + i]].normal[0]));
        transposeDoubles(plane);  // then each field's 4 lanes
        const Doubles4 denom = plane[0] * xn + plane[1] * yn + plane[2];
        const Doubles4 t = -plane[3] / denom;
        // pointsOfBatchPairs' kept (t's bits where valid and located, not
        // zero) as a mask: t > 0 has bits.
        Longs4 located;
        std::memcpy(&located, &locatedMasks[j], sizeof located);
        const Longs4 kept = (t > Doubles4{}) & ((denom >= 1e-12) | (denom <= -1e-12)) & located;
        const int keptBits = _mm256_movemask_pd(__m256d(kept));
        const Doubles4 px = xn * t, py = yn * t;
        // Per lane a point's first 4 floats: position and u.
        Lanes record[4] = {Lanes(_mm256_cvtpd_ps(__m256d(px))), Lanes(_mm256_cvtpd_ps(__m256d(py))),
                           Lanes(_mm256_cvtpd_ps(__m256d(t))), Lanes(_mm256_cvtpd_ps(__m256d(u)))};
        transpose4(record);
        auto store = [&](ScanPoint& point, int i, int edge) {
            std::memcpy(static_cast<void*>(&point), &record[i], sizeof record[i]);
            point.pixel.y = rowV;
            point.edge = edge;
        };
        // Lane i's point, as pointsOfBatchPairs keeps it; false if the output is full.
        auto add = [&](int i) {
            const int edge = edges[j + i];
            if (const int earlier = rowPoint[edge]; earlier >= 0) {
                if (record[i][2] < points[earlier].position[2]) store(points[earlier], i, edge);
                return true;
            }
            if (pointCount == maxPoints) return false;
            rowPoint[edge] = pointCount++;
            store(*next++, i, edge);
            return true;
        };
        // All 4 kept but in a batch's last 4 (and a few not located): then
        // a test per lane, whose outcome follows the batch's size, noise
        // to a branch predictor, 1 per batch rather than up to 3.
        bool room = true;
        if (keptBits == 0xf)
            room = add(0) && add(1) && add(2) && add(3);
        else
            for (int i = 0; i < 4 && room; ++i)
                if (keptBits & 1 << i) room = add(i);
        if (!room) {
            ws.pointCount = pointCount;
            ws.truncated = true;
            return false;
        }
    }
    ws.pointCount = pointCount;
    return true;
}

// The version per CPU (an ifunc, as the window kernels of simd_edges.cpp):
// the x86-64-v3 one also on v4 CPUs.
[[gnu::target("default")]] bool pointsOfBatch(DecoderWorkspace& ws, const RowRays& rays, const double* columns,
                                              const std::int32_t* edges, const std::int64_t* locatedMasks, int batch,
                                              float rowV, std::int32_t* rowPoint)
{
    return pointsOfBatchPairs(ws, rays, columns, edges, locatedMasks, batch, rowV, rowPoint);
}
[[gnu::target("arch=x86-64-v3")]] bool pointsOfBatch(DecoderWorkspace& ws, const RowRays& rays, const double* columns,
                                                     const std::int32_t* edges, const std::int64_t* locatedMasks,
                                                     int batch, float rowV, std::int32_t* rowPoint)
{
    return pointsOfBatchQuads(ws, rays, columns, edges, locatedMasks, batch, rowV, rowPoint);
}
#else
bool pointsOfBatch(DecoderWorkspace& ws, const RowRays& rays, const double* columns, const std::int32_t* edges,
                   const std::int64_t* locatedMasks, int batch, float rowV, std::int32_t* rowPoint)
{
    return pointsOfBatchPairs(ws, rays, columns, edges, locatedMasks, batch, rowV, rowPoint);
}
#endif

}  // namespace

// Cloned for x86-64-v3 and -v4 (STRIA_X86_CLONES, simd.hpp): the same
// vector code in VEX encoding, whose three-operand forms need no register
// copies, 0.9 M of 10.9 M instructions per 780x580 decode; the same floats
// (no FMA: -ffp-contract=off; golden frames identical from each clone).
STRIA_X86_CLONES void computePoints(DecoderWorkspace& ws)
{
    // Camera rows; row y's labels and borders are label row y >> shift (row pairs: y / 2).
    const int w = ws.width, h = ws.cameraHeight, shift = ws.params.segmentRowPairs ? 1 : 0;
    const Region* regions = ws.regions.get();
    const std::int32_t* labels = ws.labels.get();
    const cv::Matx33f& m = ws.colorCorrection;
    ws.pointCount = 0;
    // An image narrower than a centroid window with its peak's margins has
    // no edge to locate (each peak fails the bounds test in step 4); from
    // here on w - 2 - 2 kSearchRadius >= 0.
    if (w < 2 + 2 * kSearchRadius) return;
    // The regions' stripes in a compact array (in the scratch, free after
    // the traversal): the scan looks up two per label change, and the
    // 64-byte region records would bring one cache line each.
    std::int32_t* stripes = ws.scratch.get();
    // Undecoded regions (stripe -1) as kUndecoded, so that one test finds
    // consecutive stripes.
    for (int r = 0; r < ws.regionCount; ++r) {
        const std::int32_t stripe = regions[r].stripe, undecoded = stripe >> 31;  // all ones if < 0
        stripes[r] = (stripe & ~undecoded) | (kUndecoded & undecoded);
    }
    // Per pattern edge, the index of the current row's point of that edge
    // (-1 = none yet), in the seeding's candidate list (one entry per
    // pattern edge, free after the traversal).
    std::int32_t* rowPoint = ws.candidates.get();
    const int edgeCount = ws.pattern.edgeCount();
    const SymbolCode* symbols = ws.pattern.edgeSymbols().data();

    // A row's edges go through each step below together, a batch of up to
    // kBatch (on the stack) at a time: one loop per step, whose iterations
    // are independent, so the core overlaps several edges' divisions and
    // dependency chains; one loop over the whole chain per edge (600
    // instructions) left its latency exposed.
    constexpr int kBatch = 256;
    // Arrays from step 4 on have room for 3 more: a batch in 4 lanes.
    // Per edge at column x (the label change x, x + 1): its window's first
    // sample, x - 2 kSearchRadius (step 3's input as step 1 stores it).
    std::array<std::int32_t, kBatch + 3> firsts, edges;
    std::array<cv::Vec3f, kBatch + 3> weights;  // step 2 stores 4 floats per edge: 1 past the last
    std::array<std::array<float, kWindowSamples + 1>, kBatch + 3> samples;
    std::array<double, kBatch + 3> columns;
    std::array<std::int64_t, kBatch + 3> locatedMasks;  // all ones if located, else 0

    const unsigned peakLimit = static_cast<unsigned>(w - 2 - 2 * kSearchRadius);
    for (int y = 0; y < h; ++y) {
        const float rowV = static_cast<float>(y);
        const std::int32_t* label = labels + static_cast<std::ptrdiff_t>(y >> shift) * w;
        const std::uint8_t* row = ws.frame.row(y);
        const RowRays rays(ws, y);
        // The row's borders from the regions stage's list (in increasing
        // order); the reference is a walk of its masks (borderMask) by
        // a loop per 64-bit word, whose exit was mispredicted on most words.
        const std::uint16_t* border = ws.borderPositions + ws.borderStarts[y >> shift];
        const std::uint16_t* const bordersEnd = ws.borderPositions + ws.borderStarts[(y >> shift) + 1];
        std::fill(rowPoint, rowPoint + edgeCount, -1);
        // The next row's pixels and labels on their way to the cache while
        // this row is located: the windows read most of a row's cache lines
        // and waited for them (1388x1038: depth 3.0-3.2 -> 2.1-2.8 ms warm),
        // and the labels come from the graph stage's time, long evicted
        // (780x580: 1.09-1.14 -> 1.04-1.08 ms).
        // One loop for both, 8 label lines and 6 pixel lines per step (the
        // labels take 4 bytes a pixel, the pixels 3): an eighth of the loop
        // overhead of a loop per line (with 4 and 3, callgrind's predictor
        // missed the loop's branch 1.6 k times more per 1388x1038 decode
        // once step 1 had changed: aliasing). Addresses as integers: the
        // last step may reach up to 7 lines past either row (past the
        // buffers' ends in the last row), harmless for a prefetch, not for
        // a pointer.
        if (y + 1 < h) {
            const std::int32_t* const nextLabelRow = labels + static_cast<std::ptrdiff_t>((y + 1) >> shift) * w;
            const std::uintptr_t nextLabels = reinterpret_cast<std::uintptr_t>(nextLabelRow);
            const std::uintptr_t nextPixels = reinterpret_cast<std::uintptr_t>(ws.frame.row(y + 1));
            for (std::uintptr_t b = 0, p = 0; b < 4u * static_cast<unsigned>(w); b += 512, p += 384) {
                for (int k = 0; k < 8; ++k) __builtin_prefetch(reinterpret_cast<const void*>(nextLabels + b + 64 * k));
                for (int k = 0; k < 6; ++k) __builtin_prefetch(reinterpret_cast<const void*>(nextPixels + p + 64 * k));
            }
        }
        // 64-bit count and columns: as int, GCC sign-extended them per change.
        std::ptrdiff_t count = 0;
        // The stripe left of the next label change, plus 1: the masks mark
        // every change, so the pixels from the previous change (or the
        // row's start) to the next share a label. Carried from change to
        // change, it halves step 1's look-ups.
        std::int32_t leftStripePlus1 = stripes[label[0]] + 1;
        // Up to kBatch borders per batch.
        while (border != bordersEnd) {
            const std::uint16_t* const batchEnd = bordersEnd - border > kBatch ? border + kBatch : bordersEnd;
            // Step 1: label changes between regions decoded as consecutive
            // stripes k, k + 1, from the regions stage's border lists, gathered without a
            // branch per change: whether two neighbours share a label, and
            // whether their stripes are consecutive, is noise to a branch
            // predictor (85 000 and 22 000 mispredictions per 780x580 frame).
            // The stripe carried plus 1 (one lea for the test below, where a
            // subtraction and an increment needed a copy).
            for (; border != batchEnd; ++border) {
                const std::ptrdiff_t first = std::ptrdiff_t{*border} - 2 * kSearchRadius;
                const std::int32_t rightStripe = stripes[label[first + 2 * kSearchRadius + 1]];
                firsts[count] = static_cast<std::int32_t>(first);
                // leftStripe + 1 - rightStripe = 0 or 2 (both decoded, as kUndecoded is far from every stripe).
                count += ((static_cast<unsigned>(leftStripePlus1) - static_cast<unsigned>(rightStripe)) & ~2u) == 0;
                leftStripePlus1 = rightStripe + 1;
            }
            if (count > 0) {
                const int batch = static_cast<int>(count);
                // Step 2: weights per channel: expected sign / range, walking
                // left to right. The 3 channels in lanes (one division, and
                // a select where std::max's branch was: 3 per edge): per
                // lane numerator[c] / std::max(0.5f * (left.range[c] +
                // right.range[c]), 1.0f), the same floats. Lane 3 (range's
                // next float, centroidX, over 0) lands in the next edge's
                // weights, which that edge overwrites, or in the spare one.
                static_assert(offsetof(Region, range) + sizeof(Lanes) <= sizeof(Region));
                // The labels at x = first + 2 kSearchRadius by a 64-bit first
                // (one sign-extending load, the offset in the address), the
                // orientation and std::min(leftStripe, rightStripe) by
                // arithmetic (the stripes differ by 1; GCC compared them
                // three times, with a branch): 36 -> 28 instructions per
                // edge (780x580, x86-64-v3).
                for (int j = 0; j < batch; ++j) {
                    const std::ptrdiff_t first = firsts[j];
                    const std::int32_t leftLabel = label[first + 2 * kSearchRadius];
                    const std::int32_t rightLabel = label[first + 2 * kSearchRadius + 1];
                    const Region& left = regions[leftLabel];
                    const Region& right = regions[rightLabel];
                    const int leftStripe = stripes[leftLabel], rightStripe = stripes[rightLabel];
                    // 1 if the stripe index rises (rightStripe = leftStripe + 1), else 0.
                    const int rising = static_cast<int>(static_cast<unsigned>(leftStripe - rightStripe) >> 31);
                    const int edge = rightStripe - rising;  // std::min(leftStripe, rightStripe)
                    Lanes numerator, leftRange, rightRange;
                    std::memcpy(&numerator, &kSignedSigns[symbols[edge]][rising], sizeof numerator);
                    std::memcpy(&leftRange, left.range.data(), sizeof leftRange);
                    std::memcpy(&rightRange, right.range.data(), sizeof rightRange);
                    const Lanes one = Lanes{} + 1.0f, range = 0.5f * (leftRange + rightRange);
#if defined(__SSE2__)
                    // maxps(a, b) is a > b ? a : b: std::max(range, 1.0f) in one instruction (GCC: 4).
                    const Lanes weight = numerator / Lanes(_mm_max_ps(one, range));
#elif defined(__aarch64__)
                    const Lanes weight = numerator / Lanes(vmaxq_f32(one, range));  // one instruction (GCC: 2)
#else
                    const Lanes weight = numerator / (range < one ? one : range);  // std::max(range, 1.0f)
#endif
                    std::memcpy(reinterpret_cast<char*>(weights.data()) + sizeof(cv::Vec3f) * j, &weight, sizeof weight);
                    edges[j] = edge;
                }
                // Step 3: projected gradient at half-pixel positions i + 0.5,
                // i in [x - 2 * kSearchRadius, x + 2 * kSearchRadius]: every
                // sample both searches below can read (-inf past the image
                // border, which never wins the peak search, so that search
                // has fixed bounds). The last is read only by the centroid
                // of a peak at x + kSearchRadius: it is computed then, so
                // most edges take 8 samples (two kernel steps of 4) rather
                // than 9 (three).
                projectedGradientWindows(row, w, firsts.data(), weights.data(), batch, ws.rgbOffset, m, samples.data());
                // Step 4: the sub-pixel column of every edge, 4 edges at a
                // time, one per lane (the scalar form, per edge: below), all
                // edges: those not located (almost none) are dropped by
                // step 5's test, not by a compaction here.
                //
                // The peak: the strongest sample within kSearchRadius of x,
                // x's own on a tie, else the first (x - 2, x - 1, x + 1,
                // x + 2 in that order); by selects, not branches (which
                // sample wins is noise). Compared as int32 float bits: they
                // order the floats above 0 as the floats do and put every
                // other below them (a peak not above 0 is not used). The
                // scalar form: top = max over k of int64(bits of sample
                // x - 2 + k) x 8 + rank {3, 2, 4, 1, 0}[k], peak = x +
                // {2, 1, -1, -2, 0}[top & 7].
                // The peak must lie inside the search window with its whole
                // centroid window in the image: an edge whose profile the
                // image border cuts off cannot be located (peak -
                // kSearchRadius < 0 or peak + kSearchRadius > w - 2).
                //
                // Then the centroid of the peak's samples above a quarter of
                // its height: averages the noise over ~3 samples, and the
                // threshold keeps the tails of the neighbouring stripe edges
                // out. Sample k of window i in lane i of vector k (so the
                // sums are vector additions, not additions across lanes),
                // branch-free: a sample below the threshold counts as zero,
                // by a select (GCC compiles std::max(d, 0.0f) as a branch,
                // mispredicted 33 000 times per 780x580 frame). The sums add
                // the samples in their order, as a loop from 0 would: the
                // same floats, up to a zero moment's sign, which the column
                // does not see.
                static_assert(kSearchRadius == 2, "5 peak candidates, 5 centroid samples");
                constexpr int kCentre = 2 * kSearchRadius;  // x's sample
                for (int i = batch; i < batch + 3; ++i) {  // lanes past the last repeat it (batch > 0)
                    firsts[i] = firsts[batch - 1];
                    edges[i] = edges[batch - 1];
                    weights[i] = weights[batch - 1];
                    samples[i] = samples[batch - 1];
                }
                const Ints lowest = Ints{} + kSearchRadius, highest = lowest + static_cast<std::int32_t>(peakLimit);
                for (int j0 = 0; j0 < batch; j0 += 4) {
                    std::array<float*, 4> s;
                    for (int i = 0; i < 4; ++i) s[i] = samples[j0 + i].data();
                    // Samples x - 2 .. x + 1, then x + 2.
                    Lanes v[4];
                    for (int i = 0; i < 4; ++i) std::memcpy(&v[i], s[i] + kCentre - 2, sizeof(Lanes));
                    transpose4(v);
                    const Lanes v4{s[0][kCentre + 2], s[1][kCentre + 2], s[2][kCentre + 2], s[3][kCentre + 2]};
                    Ints top = std::bit_cast<Ints>(v[2]), offset = Ints{};
                    for (const auto& [sample, k] : {std::pair{v[0], -2}, std::pair{v[1], -1}, std::pair{v[3], 1},
                                                    std::pair{v4, 2}}) {
                        const Ints bits = std::bit_cast<Ints>(sample), greater = bits > top;
                        top = greater ? bits : top;
                        offset = greater ? Ints{} + k : offset;
                    }
                    const Lanes peakValue = std::bit_cast<Lanes>(top);
                    Ints x;
                    std::memcpy(&x, &firsts[j0], sizeof x);
                    x += 2 * kSearchRadius;
                    const Ints peak = x + offset;
                    const Ints located = (peakValue > 0) & (peak >= lowest) & (peak <= highest);
                    // The first sample of each centroid window (0 if not located).
                    const Ints first = (offset + (kCentre - kSearchRadius)) & located;
                    // The last sample (x + 4) is read only by the centroid of
                    // a peak at x + kSearchRadius: computed then.
                    for (int bits = laneBits(first == kCentre); bits; bits &= bits - 1) {
                        const int i = std::countr_zero(static_cast<unsigned>(bits));
                        projectedGradientsReference(row, x[i] + 2 * kSearchRadius, 1, ws.rgbOffset, m, weights[j0 + i],
                                                    &samples[j0 + i][2 * kCentre]);
                    }
                    Lanes d[5];
                    for (int i = 0; i < 4; ++i) std::memcpy(&d[i], s[i] + first[i], sizeof(Lanes));
                    d[4] = Lanes{s[0][first[0] + 4], s[1][first[1] + 4], s[2][first[2] + 4], s[3][first[3] + 4]};
                    const Lanes threshold = kCentroidThreshold * peakValue;
                    transpose4(d);
                    Lanes g[5];
                    for (int k = 0; k < 5; ++k) {
                        d[k] -= threshold;
                        g[k] = d[k] > 0 ? d[k] : Lanes{};
                    }
                    const Lanes sum = g[0] + g[1] + g[2] + g[3] + g[4];
                    const Lanes moment = g[0] * -2.0f + g[1] * -1.0f + g[2] * 0.0f + g[3] * 1.0f + g[4] * 2.0f;
                    // 0 where not located: a finite column for the ray look-up.
                    const Lanes subPixel = located ? moment / sum : Lanes{};
                    // Stored in pairs, as step 5 loads them, with the
                    // located masks widened to its double lanes.
                    for (int i = 0; i < 4; i += 2) {
                        const Doubles column = Doubles{static_cast<double>(peak[i]), static_cast<double>(peak[i + 1])} +
                                               0.5 + Doubles{subPixel[i], subPixel[i + 1]};
                        std::memcpy(&columns[j0 + i], &column, sizeof column);
                        const Longs mask = std::bit_cast<Longs>(__builtin_shuffle(located, Ints{i, i, i + 1, i + 1}));
                        std::memcpy(&locatedMasks[j0 + i], &mask, sizeof mask);
                    }
                }
                // Step 5: the points (pointsOfBatch, above), lanes past the
                // batch's last edge (step 4 located copies of it) kept by none.
                for (int i = batch; i < batch + 3; ++i) locatedMasks[i] = 0;
                if (!pointsOfBatch(ws, rays, columns.data(), edges.data(), locatedMasks.data(), batch, rowV, rowPoint))
                    return;
                count = 0;
            }
        }
    }
}

}  // namespace stria::pipeline
