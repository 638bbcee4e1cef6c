#include "firmware/app/stop_signals.hpp"

#include <atomic>

namespace stria::firmware {
namespace {

// The loop is published before the function and withdrawn after it, so the
// handler never calls a function with a stale loop.
std::atomic<void*> gLoop{nullptr};
std::atomic<void (*)(void*)> gRequestStop{nullptr};
volatile std::sig_atomic_t gReceived = 0;

extern "C" void onStopSignal(int signal)
{
    gReceived = signal;
    if (auto* requestStop = gRequestStop.load()) requestStop(gLoop.load());
}

}  // namespace

StopSignals::StopSignals(void (*requestStop)(void*), void* loop)
{
    gReceived = 0;
    gLoop.store(loop);
    gRequestStop.store(requestStop);
    struct sigaction action {};
    action.sa_handler = onStopSignal;
    sigemptyset(&action.sa_mask);
    // No SA_RESTART: a blocking wait returns EINTR and the loop looks at the stop flag.
    sigaction(SIGINT, &action, &previousInt_);
    sigaction(SIGTERM, &action, &previousTerm_);
}

StopSignals::~StopSignals()
{
    sigaction(SIGINT, &previousInt_, nullptr);
    sigaction(SIGTERM, &previousTerm_, nullptr);
    gRequestStop.store(nullptr);
    gLoop.store(nullptr);
}

int StopSignals::received() { return gReceived; }

}  // namespace stria::firmware
