// qrtpland: see daemon.hpp and `qrtpland --help`.
#include <atomic>
#include <csignal>
#include <cstdio>

#include "can_link.hpp"
#include "daemon.hpp"
#include "keyfile.hpp"
#include "log.hpp"
#include "options.hpp"

namespace
{
qrt::RunFlags flags;
void on_signal(int sig)
{
    if (sig == SIGUSR1)
        flags.freeze_planner = true;
    else if (sig == SIGUSR2)
        flags.freeze_guard = true;
    else
        flags.stop = true;
}
} // namespace

int main(int argc, char **argv)
{
    qrt::Options opts;
    std::string error;
    int rc = qrt::parse_options(argc, argv, &opts, &error);
    if (rc == 1) // --help or --version
        return qrt::finish_stdout("qrtpland");
    if (rc != 0) {
        std::fprintf(stderr, "qrtpland: %s\n", error.c_str());
        return 2;
    }
    if (!opts.gen_key_name.empty()) {
        qrt::SenderRole role{};
        qrt::parse_role(opts.gen_key_role, &role); // checked by the options
        if (!qrt::generate_key(opts.gen_key_dir, opts.gen_key_name, role,
                               &error)) {
            std::fprintf(stderr, "qrtpland: --gen-key: %s\n", error.c_str());
            return 2;
        }
        std::printf("%s/%s.key: the %s key: one copy with the sender, one in "
                    "qrtpland's --keys directory\n",
                    opts.gen_key_dir.c_str(), opts.gen_key_name.c_str(),
                    opts.gen_key_role.c_str());
        return 0;
    }
    qrt::LogLevel level = qrt::LogLevel::info;
    qrt::parse_log_level(opts.log_level.c_str(), &level);
    qrt::set_log_level(level);
    struct sigaction sa {
    };
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    if (opts.test_hooks) {
        sigaction(SIGUSR1, &sa, nullptr);
        sigaction(SIGUSR2, &sa, nullptr);
    }
    qrt::Daemon daemon(opts);
    return daemon.run(flags);
}
