#pragma once
// Button debouncing as a pure state machine over a timeline of line edges, so
// every button backend (GPIO, simulated) shares it and tests can feed it
// bounce sequences without hardware. A press is a release->press change of
// the debounced level: the line went active and then stayed active for the
// debounce time. Bounces shorter than that never reach the debounced level.

#include <cstdint>
#include <optional>

namespace stria::hal {

class Debouncer {
public:
    explicit Debouncer(std::int64_t debounceNs) : debounceNs_(debounceNs) {}

    // The raw line changed to `active` at time tNs (times never go backwards).
    void edge(std::int64_t tNs, bool active)
    {
        settle(tNs);
        if (active != raw_) {
            raw_ = active;
            lastEdgeNs_ = tNs;
        }
    }

    // Advances to tNs; true (once per press) if a debounced press completed by then.
    bool pressBy(std::int64_t tNs)
    {
        settle(tNs);
        if (pendingPresses_ == 0) return false;
        --pendingPresses_;
        return true;
    }

    // When the current raw level becomes debounced, if it differs from the debounced level.
    std::optional<std::int64_t> deadline() const
    {
        if (raw_ == stable_) return std::nullopt;
        return lastEdgeNs_ + debounceNs_;
    }

    bool pressed() const { return stable_; }

private:
    void settle(std::int64_t tNs)
    {
        if (raw_ == stable_ || tNs - lastEdgeNs_ < debounceNs_) return;
        stable_ = raw_;
        if (stable_) ++pendingPresses_;
    }

    std::int64_t debounceNs_;
    std::int64_t lastEdgeNs_ = 0;
    bool raw_ = false;
    bool stable_ = false;
    int pendingPresses_ = 0;
};

}  // namespace stria::hal
