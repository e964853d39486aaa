// Checked atomic writes (temporary file, flush, fsync, close, rename) and
// whole-file reads.
#include "core/file_io.h"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include <sys/stat.h>
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

void closeWrittenFile(std::FILE* f, const std::string& file) {
    int error = 0;
    errno = 0;
    // a write that failed earlier leaves the error flag set and its errno
    // possibly overwritten since: EIO then stands for it
    if (std::fflush(f) != 0 || std::ferror(f)) error = errno ? errno : EIO;
    // fsync reports write-back failures the page cache has not shown yet;
    // EINVAL/EROFS only say this file (a device, a pipe) cannot be synced.
    if (error == 0 && ::fsync(::fileno(f)) != 0 && errno != EINVAL && errno != EROFS) error = errno;
    if (std::fclose(f) != 0 && error == 0) error = errno;
    if (error != 0) throw IoError(file, std::string("write failed: ") + std::strerror(error));
}

AtomicFile::AtomicFile(std::string target) : target_(std::move(target)), temporary_(temporaryNameFor(target_)) {
    stream_ = std::fopen(temporary_.c_str(), "wb");
    if (!stream_) throw IoError(target_, std::string("cannot open for writing: ") + std::strerror(errno));
}

AtomicFile::~AtomicFile() {
    if (committed_) return;
    if (stream_) std::fclose(stream_);
    std::remove(temporary_.c_str());
}

void AtomicFile::commit() {
    std::FILE* f = std::exchange(stream_, nullptr);
    closeWrittenFile(f, target_);  // on failure the destructor removes the temporary
    commitTemporary(temporary_, target_);
    committed_ = true;
}

void writeFileAtomic(const std::string& file, std::string_view bytes) {
    AtomicFile out(file);
    errno = 0;
    if (std::fwrite(bytes.data(), 1, bytes.size(), out.stream()) != bytes.size())
        throw IoError(file, std::string("write failed: ") + std::strerror(errno ? errno : EIO));
    out.commit();
}

std::string readFileBytes(const std::string& file) {
    std::FILE* f = std::fopen(file.c_str(), "rb");
    if (!f) throw IoError(file, std::string("cannot open: ") + std::strerror(errno));
    struct stat info {};
    if (::fstat(::fileno(f), &info) != 0 || !S_ISREG(info.st_mode)) {
        std::fclose(f);
        throw IoError(file, "cannot read: not a regular file");
    }
    std::string bytes(static_cast<std::size_t>(info.st_size), '\0');
    const std::size_t got = std::fread(bytes.data(), 1, bytes.size(), f);
    const bool failed = std::ferror(f) != 0;
    std::fclose(f);
    if (failed || got != bytes.size())
        throw IoError(file, "cannot read: the file changed size or an I/O error occurred");
    return bytes;
}

}  // namespace terrain
