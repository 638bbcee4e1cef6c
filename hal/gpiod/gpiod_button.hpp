#pragma once
// The scan button on a GPIO input line: the kernel timestamps both edges, the
// shared Debouncer turns them into presses, and waitForPress() sleeps in
// poll() on the line's event fd and an eventfd that interrupt() writes.

#include "hal/button.hpp"
#include "hal/debouncer.hpp"
#include "hal/gpiod/gpiod_line.hpp"

#include <memory>
#include <string>

namespace stria::hal {

class GpiodButton final : public Button {
public:
    static Result<std::unique_ptr<GpiodButton>> open(const std::string& chip, int line, bool activeLow, int debounceMs);
    // `line` must be requested for both edges.
    static Result<std::unique_ptr<GpiodButton>> open(std::unique_ptr<GpiodLine> line, int debounceMs);
    ~GpiodButton() override;

    Result<ButtonWait> waitForPress(std::chrono::milliseconds timeout) override;
    void interrupt() override;  // one write() to an eventfd

private:
    GpiodButton(std::unique_ptr<GpiodLine> line, int debounceMs, int interruptFd);
    Status feedPendingEdges();  // reads the edges queued in the kernel, without waiting

    std::unique_ptr<GpiodLine> line_;
    Debouncer debouncer_;
    std::int64_t lastTimeNs_ = 0;  // the Debouncer is fed in time order
    int interruptFd_;
};

}  // namespace stria::hal
