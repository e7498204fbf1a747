#include "lcm_loss.hpp"

#include <dirent.h>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <unistd.h>

namespace qrt
{

namespace
{

// The inodes of this process's sockets, from /proc/self/fd's links.
std::set<unsigned long> socket_inodes()
{
    std::set<unsigned long> inodes;
    DIR *dir = opendir("/proc/self/fd");
    if (!dir)
        return inodes;
    while (dirent *e = readdir(dir)) {
        std::string path = std::string("/proc/self/fd/") + e->d_name;
        char target[64];
        ssize_t n = readlink(path.c_str(), target, sizeof target - 1);
        if (n <= 0)
            continue;
        target[n] = '\0';
        unsigned long inode = 0;
        if (std::sscanf(target, "socket:[%lu]", &inode) == 1)
            inodes.insert(inode);
    }
    closedir(dir);
    return inodes;
}

// The drops column of the table's lines whose inode is ours. Columns: sl
// local rem st tx:rx tr:when retrnsmt uid timeout inode ref pointer drops.
int64_t drops_in(const char *table, const std::set<unsigned long> &ours)
{
    std::ifstream in(table);
    std::string line;
    int64_t sum = 0;
    std::getline(in, line); // the header
    while (std::getline(in, line)) {
        std::istringstream f(line);
        std::string col[13];
        for (auto &c : col)
            f >> c;
        if (!f)
            continue;
        unsigned long inode = std::strtoul(col[9].c_str(), nullptr, 10);
        if (ours.count(inode))
            sum += std::strtoll(col[12].c_str(), nullptr, 10);
    }
    return sum;
}

} // namespace

int64_t lcm_datagrams_lost()
{
    std::set<unsigned long> ours = socket_inodes();
    if (ours.empty())
        return 0;
    return drops_in("/proc/net/udp", ours) + drops_in("/proc/net/udp6", ours);
}

} // namespace qrt
