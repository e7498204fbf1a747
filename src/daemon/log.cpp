#include "log.hpp"

#include <atomic>
#include <cstdio>
#include <cstring>
#include <mutex>

namespace qrt
{

namespace
{
std::atomic<int> current{int(LogLevel::info)};
std::mutex mu;
const char *names[] = {"error", "warn", "info", "debug"};
} // namespace

void set_log_level(LogLevel level)
{
    current = int(level);
}

bool parse_log_level(const char *name, LogLevel *level)
{
    for (int i = 0; i < 4; i++)
        if (std::strcmp(name, names[i]) == 0) {
            *level = LogLevel(i);
            return true;
        }
    return false;
}

void log(LogLevel level, const char *fmt, ...)
{
    if (int(level) > current)
        return;
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    std::lock_guard<std::mutex> lock(mu);
    std::fprintf(stderr, "qrtpland: %s: %s\n", names[int(level)], line);
}

} // namespace qrt
