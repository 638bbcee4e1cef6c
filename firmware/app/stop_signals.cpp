#include "firmware/app/stop_signals.hpp"

#include <atomic>

namespace stria::firmware {
namespace {

std::atomic<Scanner*> gScanner{nullptr};
volatile std::sig_atomic_t gReceived = 0;

extern "C" void onStopSignal(int signal)
{
    gReceived = signal;
    if (Scanner* scanner = gScanner.load()) scanner->requestStop();
}

}  // namespace

StopSignals::StopSignals(Scanner& scanner)
{
    gReceived = 0;
    gScanner.store(&scanner);
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
    gScanner.store(nullptr);
}

int StopSignals::received() { return gReceived; }

}  // namespace stria::firmware
