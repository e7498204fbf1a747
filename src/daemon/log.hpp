// Log lines on stderr: "qrtpland: LEVEL: message", filtered by level.
#pragma once

#include <cstdarg>

namespace qrt
{

enum class LogLevel { error = 0, warn = 1, info = 2, debug = 3 };

void set_log_level(LogLevel level);
bool parse_log_level(const char *name, LogLevel *level);
void log(LogLevel level, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

} // namespace qrt
