#pragma once
// SIGINT and SIGTERM (Ctrl-C, systemctl stop) call the loop's requestStop()
// (Scanner, Streamer) from the signal handler: it switches the LED off with
// one write and wakes the waits, and the loop then ends cleanly. The previous
// handlers come back when this object goes away.
#include <csignal>

namespace stria::firmware {

class StopSignals {
public:
    // `Loop::requestStop()` must be async-signal-safe.
    template <typename Loop>
    explicit StopSignals(Loop& loop) : StopSignals([](void* l) { static_cast<Loop*>(l)->requestStop(); }, &loop)
    {
    }
    ~StopSignals();
    StopSignals(const StopSignals&) = delete;
    StopSignals& operator=(const StopSignals&) = delete;

    // The signal that asked for the stop, 0 if none.
    static int received();

private:
    StopSignals(void (*requestStop)(void*), void* loop);

    struct sigaction previousInt_ {};
    struct sigaction previousTerm_ {};
};

}  // namespace stria::firmware
