// Region graph kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd_graph.hpp"

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
    return graph_kernels::borderMask(a, b, count);
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
