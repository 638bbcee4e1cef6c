#include "firmware/cli.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>

namespace stria::firmware {

namespace {
std::vector<Command>& registry()
{
    static std::vector<Command> all;
    return all;
}
}  // namespace

void registerCommand(const Command& command)
{
    auto& all = registry();
    all.push_back(command);
    std::sort(all.begin(), all.end(), [](const Command& a, const Command& b) { return std::string(a.name) < b.name; });
}

const std::vector<Command>& commands() { return registry(); }

Args::Args(std::span<const std::string> args, std::vector<std::string> valueOptions, std::vector<std::string> flags)
{
    auto contains = [](const std::vector<std::string>& v, const std::string& s) {
        return std::find(v.begin(), v.end(), s) != v.end();
    };
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "-h" || a == "--help") {
            help_ = true;
            continue;
        }
        if (a.rfind("--", 0) != 0 || a.size() == 2) {
            positional_.push_back(a);
            continue;
        }
        std::string name = a.substr(2);
        std::optional<std::string> inlineValue;
        if (const auto eq = name.find('='); eq != std::string::npos) {
            inlineValue = name.substr(eq + 1);
            name = name.substr(0, eq);
        }
        if (contains(flags, name)) {
            if (inlineValue) {
                error_ = "option --" + name + " takes no value";
                return;
            }
            values_[name] = "";
        } else if (contains(valueOptions, name)) {
            if (inlineValue) {
                values_[name] = *inlineValue;
            } else if (i + 1 < args.size()) {
                values_[name] = args[++i];
            } else {
                error_ = "option --" + name + " needs a value";
                return;
            }
        } else {
            error_ = "unknown option --" + name;
            return;
        }
    }
}

bool Args::has(const std::string& name) const { return values_.count(name) != 0; }

std::optional<std::string> Args::value(const std::string& name) const
{
    const auto it = values_.find(name);
    if (it == values_.end()) return std::nullopt;
    return it->second;
}

std::string Args::valueOr(const std::string& name, const std::string& fallback) const
{
    return value(name).value_or(fallback);
}

long Args::integer(const std::string& name, long fallback)
{
    const auto v = value(name);
    if (!v) return fallback;
    long out = 0;
    const auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), out);
    if (ec != std::errc() || ptr != v->data() + v->size()) {
        if (error_.empty()) error_ = "option --" + name + " expects a whole number, not '" + *v + "'";
        return fallback;
    }
    return out;
}

double Args::number(const std::string& name, double fallback)
{
    const auto v = value(name);
    if (!v) return fallback;
    char* end = nullptr;
    const double out = std::strtod(v->c_str(), &end);
    if (v->empty() || end != v->c_str() + v->size()) {
        if (error_.empty()) error_ = "option --" + name + " expects a number, not '" + *v + "'";
        return fallback;
    }
    return out;
}

bool Args::require(const std::vector<std::string>& required)
{
    for (const auto& name : required) {
        if (!has(name)) {
            if (error_.empty()) error_ = "missing required option --" + name;
            return false;
        }
    }
    return true;
}

int usageError(const Command& command, const std::string& message)
{
    std::fprintf(stderr, "stria %s: %s\n\n%s\n", command.name, message.c_str(), command.usage);
    return kExitUsage;
}

int failure(const char* commandName, const std::string& message)
{
    std::fprintf(stderr, "stria %s: error: %s\n", commandName, message.c_str());
    return kExitFailure;
}

}  // namespace stria::firmware
