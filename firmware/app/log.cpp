#include "firmware/app/log.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstdlib>

namespace stria::firmware {
namespace {

void logLine(FILE* stream, int priority, const char* format, va_list args)
{
    static const bool journal = std::getenv("JOURNAL_STREAM") != nullptr;
    char line[1024];
    std::vsnprintf(line, sizeof line, format, args);
    // One fprintf per line so lines from the watchdog thread never interleave.
    if (journal)
        std::fprintf(stream, "<%d>%s\n", priority, line);
    else
        std::fprintf(stream, "%s\n", line);
    std::fflush(stream);
}

}  // namespace

#define STRIA_LOG(stream, priority)          \
    va_list args;                           \
    va_start(args, format);                 \
    logLine(stream, priority, format, args); \
    va_end(args)

void logInfo(const char* format, ...) { STRIA_LOG(stdout, 6); }
void logWarning(const char* format, ...) { STRIA_LOG(stderr, 4); }
void logError(const char* format, ...) { STRIA_LOG(stderr, 3); }

}  // namespace stria::firmware
