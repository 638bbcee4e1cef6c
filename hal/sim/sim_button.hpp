#pragma once
// The simulated scan button: replays a press script through the same
// Debouncer a GPIO button uses. Script syntax: comma-separated press times in
// ms from the first waitForPress() (the loop being ready), a "b" suffix makes that press bounce
// ("100,900b,1500"). Each press holds the button down for kHoldMs.
//
// In simulated time waitForPress() returns each press at once (tests run as
// fast as the pipeline); in real time it sleeps until the press is due. When
// the script is used up, waitForPress() returns Interrupted: the simulated
// operator has gone home, which ends the scan loop like a shutdown would.

#include "hal/button.hpp"
#include "hal/debouncer.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace stria::hal::sim {

struct ScriptedPress {
    int timeMs = 0;
    bool bounce = false;
};

// Parses "100,900b,1500"; errors name the bad item. Times must not decrease.
Result<std::vector<ScriptedPress>> parsePressScript(const std::string& script);

class SimButton final : public Button {
public:
    static constexpr int kHoldMs = 100;

    // Never fails; `debounceMs` as for a GPIO button.
    SimButton(std::vector<ScriptedPress> presses, int debounceMs, bool realTime);
    ~SimButton() override;

    Result<ButtonWait> waitForPress(std::chrono::milliseconds timeout) override;
    void interrupt() override;

private:
    struct Edge {
        std::int64_t timeNs;
        bool active;
    };

    std::vector<Edge> edges_;  // the raw line, from the script
    std::size_t nextEdge_ = 0;
    Debouncer debouncer_;
    bool realTime_;
    std::int64_t startNs_ = 0;  // monotonic time of the first wait
    std::int64_t nowNs_ = 0;   // simulated time since start
    int interruptFd_ = -1;     // eventfd: interrupt() is one write()
};

}  // namespace stria::hal::sim
