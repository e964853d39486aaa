#pragma once
// Helpers shared by the benchmark mains: medians and the machine description
// every results file starts with.
#include <algorithm>
#include <fstream>
#include <string>
#include <sys/utsname.h>
#include <thread>
#include <vector>

namespace terrain::bench {

inline double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

inline std::string cpuName() {
    std::ifstream f("/proc/cpuinfo");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}

/// "<cpu>, <n> hardware threads, <kernel>": the machine line of a results file.
inline std::string machineDescription() {
    utsname u{};
    uname(&u);
    return cpuName() + ", " + std::to_string(std::thread::hardware_concurrency()) + " hardware threads, " +
           u.sysname + " " + u.release;
}

}  // namespace terrain::bench
