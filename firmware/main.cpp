// stria: the scanner head's program. `stria COMMAND --help` for each command.
#include "firmware/cli.hpp"

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

using stria::firmware::commands;

static void printOverview()
{
    std::printf("stria: single-shot structured-light scanner firmware\n\nusage: stria COMMAND [OPTIONS]\n\ncommands:\n");
    for (const auto& c : commands()) std::printf("  %-10s %s\n", c.name, c.summary);
    std::printf("\n`stria COMMAND --help` describes a command's options.\n");
}

int main(int argc, char** argv)
{
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
        printOverview();
        return argc < 2 ? stria::firmware::kExitUsage : stria::firmware::kExitOk;
    }
    if (!std::strcmp(argv[1], "--version")) {
        std::printf("stria %s\n", STRIA_VERSION);
        return 0;
    }
    const std::vector<std::string> args(argv + 2, argv + argc);
    for (const auto& c : commands()) {
        if (c.name == std::string(argv[1])) {
            for (const auto& a : args) {
                if (a == "--help" || a == "-h") {
                    std::printf("%s\n", c.usage);
                    return 0;
                }
            }
            return c.run(args);
        }
    }
    std::fprintf(stderr, "stria: unknown command '%s'\n\n", argv[1]);
    printOverview();
    return stria::firmware::kExitUsage;
}
