// The suite's main: one core (OpenCV's thread pool off, so the Sobel
// reference is single-threaded like the decoder), and a non-zero exit when a
// benchmark reported an error, so a broken decode fails the ctest smoke run
// (under qemu for arm64) instead of printing a time.
#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include <cstdio>

namespace {

class ErrorCountingReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override
    {
        for (const Run& run : runs) errors_ += run.error_occurred ? 1 : 0;
        ConsoleReporter::ReportRuns(runs);
    }
    int errors() const { return errors_; }

private:
    int errors_ = 0;
};

}  // namespace

int main(int argc, char** argv)
{
    cv::setNumThreads(0);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
    ErrorCountingReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    if (reporter.errors() > 0) {
        std::fprintf(stderr, "stria_bench: %d benchmark(s) reported an error\n", reporter.errors());
        return 1;
    }
    return 0;
}
