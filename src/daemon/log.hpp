// Log lines on stderr: "qrtpland: LEVEL: message", filtered by level.
// Control characters in a message (which may quote what a stranger sent)
// are written as \xNN, so that no message can forge or hide a log line.
#pragma once

#include <cstdarg>

namespace qrt
{

enum class LogLevel { error = 0, warn = 1, info = 2, debug = 3 };

void set_log_level(LogLevel level);
bool parse_log_level(const char *name, LogLevel *level);
void log(LogLevel level, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

// For what the outside can cause at any rate (refused messages): at most
// kLimitedBurst lines at once and kLimitedPerSecond a second after that;
// the others are counted, and the next line written says how many.
constexpr int kLimitedBurst = 10;
constexpr int kLimitedPerSecond = 2;
void log_limited(LogLevel level, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
long log_lines_suppressed();

} // namespace qrt
