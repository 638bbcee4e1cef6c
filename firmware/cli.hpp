#pragma once
// The `stria` command line: one file per subcommand under firmware/commands/,
// each registering itself with STRIA_COMMAND. Exit codes: 0 success,
// 1 the work failed (message on stderr), 2 the command line was wrong.

#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace stria::firmware {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

struct Command {
    const char* name;
    const char* summary;
    const char* usage;  // full help text, printed by `stria NAME --help`
    int (*run)(std::span<const std::string> args);
};

void registerCommand(const Command& command);
const std::vector<Command>& commands();

struct CommandRegistration {
    explicit CommandRegistration(const Command& command) { registerCommand(command); }
};
#define STRIA_COMMAND(id, command) static const ::stria::firmware::CommandRegistration id##Registration{command}

// Options of the form --name VALUE, --name=VALUE and flags --name. Unknown
// options and missing values are usage errors that name the option.
class Args {
public:
    // `valueOptions` take a value, `flags` do not.
    Args(std::span<const std::string> args, std::vector<std::string> valueOptions, std::vector<std::string> flags);

    bool ok() const { return error_.empty(); }
    const std::string& error() const { return error_; }
    bool helpRequested() const { return help_; }

    bool has(const std::string& name) const;
    std::optional<std::string> value(const std::string& name) const;
    std::string valueOr(const std::string& name, const std::string& fallback) const;
    // Parsed numbers; a malformed number sets error() and returns the fallback.
    long integer(const std::string& name, long fallback);
    double number(const std::string& name, double fallback);
    const std::vector<std::string>& positional() const { return positional_; }
    // Fails unless every name in `required` is present.
    bool require(const std::vector<std::string>& required);

private:
    std::map<std::string, std::string> values_;
    std::vector<std::string> positional_;
    std::string error_;
    bool help_ = false;
};

// Prints "stria NAME: message" to stderr and returns kExitUsage / kExitFailure.
int usageError(const Command& command, const std::string& message);
int failure(const char* commandName, const std::string& message);

}  // namespace stria::firmware
