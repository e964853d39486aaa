// Atomic file writes: a temporary name beside the target, then a rename.
#include "core/file_io.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include <unistd.h>

#include "core/error.h"

namespace terrain {

std::string temporaryNameFor(const std::string& file) {
    static std::atomic<unsigned> counter{0};
    return file + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

void commitTemporary(const std::string& tmp, const std::string& file) {
    if (std::rename(tmp.c_str(), file.c_str()) != 0) {
        const std::string why = std::strerror(errno);
        std::remove(tmp.c_str());
        throw IoError(file, "cannot move the finished file into place: " + why);
    }
}

void writeFileAtomic(const std::string& file, const std::string& bytes) {
    const std::string tmp = temporaryNameFor(file);
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw IoError(file, std::string("cannot open for writing: ") + std::strerror(errno));
    const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    const bool closed = std::fclose(f) == 0;
    if (!ok || !closed) {
        std::remove(tmp.c_str());
        throw IoError(file, "write failed (disk full?)");
    }
    commitTemporary(tmp, file);
}

}  // namespace terrain
