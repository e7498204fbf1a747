#include "log.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <mutex>
#include <string>
#include <thread>

namespace qrt
{

namespace
{
std::atomic<int> current{int(LogLevel::info)};
std::mutex mu;
const char *names[] = {"error", "warn", "info", "debug"};
// log_limited's token bucket (under mu)
double tokens = kLimitedBurst;
std::chrono::steady_clock::time_point refilled =
    std::chrono::steady_clock::now();
long suppressed_since_last = 0;
std::atomic<long> suppressed_total{0};

// Lines are written to stderr by a thread of their own: a thread that
// guards motion must never wait on a slow terminal, file or pipe (nor
// hold a lock while it does). The queue is bounded; lines beyond it are
// counted and the count written when there is room again.
class Writer
{
  public:
    Writer() : thread_([this] { run(); })
    {
    }
    ~Writer() // at exit: everything queued is written first
    {
        {
            std::lock_guard<std::mutex> lock(mu_);
            stop_ = true;
        }
        wake_.notify_one();
        thread_.join();
    }
    void put(std::string line)
    {
        {
            std::lock_guard<std::mutex> lock(mu_);
            if (lines_.size() >= kMaxQueued) {
                dropped_++;
                return;
            }
            if (dropped_ > 0) {
                lines_.push_back("qrtpland: warn: " + std::to_string(dropped_) +
                                 " log lines dropped (stderr too slow)\n");
                dropped_ = 0;
            }
            lines_.push_back(std::move(line));
        }
        wake_.notify_one();
    }

  private:
    static constexpr size_t kMaxQueued = 1024;
    void run()
    {
        std::unique_lock<std::mutex> lock(mu_);
        while (true) {
            wake_.wait(lock, [&] { return stop_ || !lines_.empty(); });
            if (lines_.empty())
                return; // stop_, and all written
            std::string line = std::move(lines_.front());
            lines_.pop_front();
            lock.unlock();
            std::fputs(line.c_str(), stderr);
            lock.lock();
        }
    }
    std::mutex mu_;
    std::condition_variable wake_;
    std::deque<std::string> lines_;
    long dropped_ = 0;
    bool stop_ = false;
    std::thread thread_;
};

Writer &writer()
{
    static Writer w;
    return w;
}

// The line with every control character as \xNN.
std::string escaped(const char *line)
{
    std::string out;
    for (const char *p = line; *p; p++) {
        unsigned char c = static_cast<unsigned char>(*p);
        if (c < 0x20 || c == 0x7f) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", c);
            out += hex;
        } else {
            out += char(c);
        }
    }
    return out;
}

void write_line(LogLevel level, const char *fmt, va_list ap, bool limited)
{
    char line[1024];
    std::vsnprintf(line, sizeof line, fmt, ap);
    std::string text = escaped(line);
    std::lock_guard<std::mutex> lock(mu);
    if (limited) {
        auto now = std::chrono::steady_clock::now();
        tokens += kLimitedPerSecond *
                  std::chrono::duration<double>(now - refilled).count();
        if (tokens > kLimitedBurst)
            tokens = kLimitedBurst;
        refilled = now;
        if (tokens < 1.0) {
            suppressed_since_last++;
            suppressed_total++;
            return;
        }
        tokens -= 1.0;
    }
    if (suppressed_since_last > 0) {
        text += " (" + std::to_string(suppressed_since_last) +
                " lines like it suppressed before this one)";
        suppressed_since_last = 0;
    }
    writer().put(std::string("qrtpland: ") + names[int(level)] + ": " + text +
                 "\n");
}
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
    va_list ap;
    va_start(ap, fmt);
    write_line(level, fmt, ap, false);
    va_end(ap);
}

void log_limited(LogLevel level, const char *fmt, ...)
{
    if (int(level) > current)
        return;
    va_list ap;
    va_start(ap, fmt);
    write_line(level, fmt, ap, true);
    va_end(ap);
}

long log_lines_suppressed()
{
    return suppressed_total;
}

} // namespace qrt
