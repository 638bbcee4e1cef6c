#pragma once
// One line per event on stdout (info) or stderr (warnings, errors). Under
// systemd (JOURNAL_STREAM set) each line carries a "<N>" priority prefix
// that journald turns into the entry's priority.

namespace stria::firmware {

void logInfo(const char* format, ...) __attribute__((format(printf, 1, 2)));
void logWarning(const char* format, ...) __attribute__((format(printf, 1, 2)));
void logError(const char* format, ...) __attribute__((format(printf, 1, 2)));

}  // namespace stria::firmware
