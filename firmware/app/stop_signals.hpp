#pragma once
// SIGINT and SIGTERM (Ctrl-C, systemctl stop) call Scanner::requestStop() from
// the signal handler: it switches the LED off with one write and wakes the
// button, and the loop then ends cleanly. The previous handlers come back when
// this object goes away.
#include "firmware/app/scanner.hpp"

#include <csignal>

namespace stria::firmware {

class StopSignals {
public:
    explicit StopSignals(Scanner& scanner);
    ~StopSignals();
    StopSignals(const StopSignals&) = delete;
    StopSignals& operator=(const StopSignals&) = delete;

    // The signal that asked for the stop, 0 if none.
    static int received();

private:
    struct sigaction previousInt_ {};
    struct sigaction previousTerm_ {};
};

}  // namespace stria::firmware
