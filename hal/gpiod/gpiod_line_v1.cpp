// GpiodLine with the libgpiod 1.6 API (gpiod_chip_open_lookup,
// gpiod_line_request_output_flags, gpiod_line_request_both_edges_events_flags).
#include "hal/gpiod/gpiod_line.hpp"

#include <gpiod.h>

#include <cerrno>
#include <cstring>

namespace stria::hal {
namespace {

constexpr const char* kConsumer = "stria";

class GpiodLineV1 final : public GpiodLine {
public:
    GpiodLineV1(gpiod_chip* chip, gpiod_line* line, std::string name) : chip_(chip), line_(line), name_(std::move(name)) {}
    ~GpiodLineV1() override
    {
        gpiod_line_release(line_);
        gpiod_chip_close(chip_);
    }

    const std::string& name() const override { return name_; }
    int setValue(bool active) override { return gpiod_line_set_value(line_, active ? 1 : 0) < 0 ? -errno : 0; }
    int value() override
    {
        const int v = gpiod_line_get_value(line_);
        return v < 0 ? -errno : v;
    }
    int eventFd() const override { return gpiod_line_event_get_fd(line_); }

    int readEdges(LineEdge* edges, int capacity) override
    {
        gpiod_line_event events[16];
        const int count = gpiod_line_event_read_multiple(line_, events, unsigned(std::min(capacity, 16)));
        if (count < 0) return -errno;
        for (int i = 0; i < count; ++i)
            edges[i] = {std::int64_t(events[i].ts.tv_sec) * 1'000'000'000 + events[i].ts.tv_nsec,
                        events[i].event_type == GPIOD_LINE_EVENT_RISING_EDGE};
        return count;
    }

private:
    gpiod_chip* chip_;
    gpiod_line* line_;
    std::string name_;
};

}  // namespace

std::string gpioErrorMessage(const std::string& name, const std::string& what, int error)
{
    std::string message = "GPIO " + name + ": " + what + ": " + std::strerror(error);
    if (error == ENOENT) message += " (`gpiodetect` lists the chips)";
    if (error == EACCES || error == EPERM) message += " (add the user to group 'gpio')";
    return message;
}

Result<std::unique_ptr<GpiodLine>> GpiodLine::request(const std::string& chipName, int offset, bool activeLow,
                                                      Mode mode)
{
    gpiod_chip* chip = gpiod_chip_open_lookup(chipName.c_str());
    if (!chip) return Status::error(gpioErrorMessage("chip '" + chipName + "'", "cannot open", errno));
    const std::string name = "line " + std::to_string(offset) + " of '" + chipName + "'";
    const unsigned lines = gpiod_chip_num_lines(chip);
    gpiod_line* line = offset >= 0 && unsigned(offset) < lines ? gpiod_chip_get_line(chip, unsigned(offset)) : nullptr;
    if (!line) {
        const std::string label = gpiod_chip_label(chip);
        gpiod_chip_close(chip);
        return Status::error("GPIO chip '" + chipName + "' (" + label + ") has no line " + std::to_string(offset) +
                             " (it has " + std::to_string(lines) + ")");
    }
    const int flags = activeLow ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
    const int ret = mode == Mode::Output ? gpiod_line_request_output_flags(line, kConsumer, flags, 0)
                                         : gpiod_line_request_both_edges_events_flags(line, kConsumer, flags);
    if (ret < 0) {
        const int error = errno;
        std::string message = gpioErrorMessage(
            name, mode == Mode::Output ? "cannot request as output" : "cannot request edge events", error);
        if (error == EBUSY && gpiod_line_consumer(line))
            message += std::string(" (in use by '") + gpiod_line_consumer(line) + "')";
        gpiod_chip_close(chip);
        return Status::error(message);
    }
    return std::unique_ptr<GpiodLine>(std::make_unique<GpiodLineV1>(chip, line, name));
}

}  // namespace stria::hal
