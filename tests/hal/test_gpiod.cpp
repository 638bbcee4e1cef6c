// GpiodLight and GpiodButton over an emulated GPIO line (no gpio-sim here):
// the line's event fd is a pipe the test writes edges into, so the real
// poll()/eventfd/debounce code runs. The libgpiod 1.6 layer itself is covered
// by its error path (a chip that does not exist).
#include "hal/clock.hpp"
#include "hal/gpiod/gpiod_button.hpp"
#include "hal/gpiod/gpiod_light.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <deque>
#include <thread>

namespace stria::hal {
namespace {

using namespace std::chrono_literals;
constexpr std::int64_t kMs = 1'000'000;

class FakeLine final : public GpiodLine {
public:
    FakeLine() { EXPECT_EQ(::pipe2(pipe_, O_NONBLOCK | O_CLOEXEC), 0); }
    ~FakeLine() override
    {
        ::close(pipe_[0]);
        ::close(pipe_[1]);
    }

    void pushEdge(std::int64_t timeNs, bool active)
    {
        edges_.push_back({timeNs, active});
        const char byte = 1;
        ASSERT_EQ(::write(pipe_[1], &byte, 1), 1);
    }

    const std::string& name() const override { return name_; }
    int setValue(bool active) override
    {
        if (failWith_) return -failWith_;
        value_ = active;
        ++writes_;
        return 0;
    }
    int value() override { return value_; }
    int eventFd() const override { return pipe_[0]; }
    int readEdges(LineEdge* edges, int capacity) override
    {
        char bytes[64];
        while (::read(pipe_[0], bytes, sizeof bytes) > 0) {}
        int count = 0;
        for (; count < capacity && !edges_.empty(); ++count) {
            edges[count] = edges_.front();
            edges_.pop_front();
        }
        return count;
    }

    int failWith_ = 0;
    bool value_ = false;
    int writes_ = 0;

private:
    std::string name_ = "line 17 of 'gpiochip0'";
    int pipe_[2] = {-1, -1};
    std::deque<LineEdge> edges_;
};

struct Fixture {
    FakeLine* line;
    std::unique_ptr<GpiodButton> button;
};

Fixture makeButton(int debounceMs = 20)
{
    auto line = std::make_unique<FakeLine>();
    FakeLine* raw = line.get();
    auto button = GpiodButton::open(std::move(line), debounceMs);
    EXPECT_TRUE(button.isOk()) << button.message();
    return {raw, std::move(*button)};
}

TEST(GpiodButton, BouncyPressAndReleaseGiveExactlyOnePress)
{
    auto [line, button] = makeButton();
    const std::int64_t t0 = monotonicNs() - 500 * kMs;  // already happened, as events queued in the kernel
    for (std::int64_t ms : {0, 1, 2, 3, 4}) line->pushEdge(t0 + ms * kMs, ms % 2 == 0);
    for (std::int64_t ms : {200, 201, 202, 203}) line->pushEdge(t0 + ms * kMs, ms % 2 == 1);  // release chatter
    line->pushEdge(t0 + 204 * kMs, false);
    auto first = button->waitForPress(1s);
    ASSERT_TRUE(first.isOk()) << first.message();
    EXPECT_EQ(*first, ButtonWait::Pressed);
    auto second = button->waitForPress(60ms);
    ASSERT_TRUE(second.isOk()) << second.message();
    EXPECT_EQ(*second, ButtonWait::TimedOut);
}

TEST(GpiodButton, PressIsReportedOnlyOnceTheLineStayedActive)
{
    auto [line, button] = makeButton(30);
    // Active now: waitForPress() has to wake at the debounce deadline by itself.
    line->pushEdge(monotonicNs(), true);
    const std::int64_t start = monotonicNs();
    auto wait = button->waitForPress(2s);
    ASSERT_TRUE(wait.isOk()) << wait.message();
    EXPECT_EQ(*wait, ButtonWait::Pressed);
    EXPECT_GE(monotonicNs() - start, 29 * kMs);  // not before the line was stable for 30 ms
}

TEST(GpiodButton, GlitchShorterThanDebounceTimesOut)
{
    auto [line, button] = makeButton(20);
    const std::int64_t now = monotonicNs();
    line->pushEdge(now, true);
    line->pushEdge(now + 5 * kMs, false);
    auto wait = button->waitForPress(100ms);
    ASSERT_TRUE(wait.isOk()) << wait.message();
    EXPECT_EQ(*wait, ButtonWait::TimedOut);
}

TEST(GpiodButton, InterruptWakesAWaitingCall)
{
    auto [line, button] = makeButton();
    std::thread shutdown([b = button.get()] {
        std::this_thread::sleep_for(30ms);
        b->interrupt();
    });
    auto wait = button->waitForPress(10s);
    shutdown.join();
    ASSERT_TRUE(wait.isOk()) << wait.message();
    EXPECT_EQ(*wait, ButtonWait::Interrupted);
    // Consumed: the next wait is an ordinary one.
    EXPECT_EQ(*button->waitForPress(10ms), ButtonWait::TimedOut);
}

TEST(GpiodLight, SetIsOneLineWriteAndReportsFailures)
{
    auto line = std::make_unique<FakeLine>();
    FakeLine* raw = line.get();
    GpiodLight light(std::move(line));
    EXPECT_FALSE(light.isOn());
    ASSERT_TRUE(light.set(true).isOk());
    EXPECT_TRUE(raw->value_);
    EXPECT_TRUE(light.isOn());
    EXPECT_EQ(raw->writes_, 1);
    raw->failWith_ = ENODEV;
    Status status = light.set(false);
    EXPECT_EQ(status.message(), "GPIO line 17 of 'gpiochip0': cannot switch off: No such device");
    EXPECT_TRUE(light.isOn());  // still on as far as anyone can tell: the caller must know
}

TEST(Gpiod, MissingChipIsNamedInTheError)
{
    auto light = GpiodLight::open("gpiochip-stria-missing", 17, false);
    ASSERT_FALSE(light.isOk());
    EXPECT_EQ(light.message(),
              "GPIO chip 'gpiochip-stria-missing': cannot open: No such file or directory (`gpiodetect` lists the chips)");
    auto button = GpiodButton::open("gpiochip-stria-missing", 27, true, 20);
    ASSERT_FALSE(button.isOk());
    EXPECT_EQ(button.message(), light.message());
}

}  // namespace
}  // namespace stria::hal
