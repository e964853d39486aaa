#pragma once
// Files for the I/O tests: a scratch folder of the test's own, whole-file
// reads and writes.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <unistd.h>

namespace terrain::test {

/// An empty folder under the system's temporary directory, named for the
/// test (`tag`) and the process, so parallel runs never share one.
inline std::filesystem::path scratchDir(const std::string& tag) {
    const std::filesystem::path p =
        std::filesystem::temp_directory_path() / ("terrain_test_" + tag + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(p);
    std::filesystem::create_directories(p);
    return p;
}

inline std::string readBytes(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

inline void writeBytes(const std::filesystem::path& p, const std::string& b) {
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    f.write(b.data(), static_cast<std::streamsize>(b.size()));
}

}  // namespace terrain::test
