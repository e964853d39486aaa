#pragma once
// What every fuzz target shares: the input as a file for the readers that
// take a path, and the one outcome besides success that is not a finding, a
// terrain::Error with a message fit for the user's one error line.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>

#include "core/error.h"

namespace terrain::fuzz {

/// A file holding the current input, named with the extension the reader
/// dispatches on. In /dev/shm (memory, no disk traffic) where there is one.
/// The name is the same on every run and machine: readers compare and quote
/// the path, libFuzzer learns from those comparisons, and a seeded run must
/// see the same bytes to fuzz the same inputs. Parallel jobs (-jobs=N) set
/// TERRAIN_FUZZ_JOB to a name of their own.
class InputFile {
public:
    explicit InputFile(const std::string& extension) {
        std::error_code ec;
        std::filesystem::path dir = "/dev/shm";
        if (!std::filesystem::is_directory(dir, ec)) dir = std::filesystem::temp_directory_path();
        const char* job = std::getenv("TERRAIN_FUZZ_JOB");
        path_ = (dir / ("terrain-fuzz-input" + std::string(job ? job : "") + extension)).string();
    }
    ~InputFile() { std::remove(path_.c_str()); }
    InputFile(const InputFile&) = delete;
    InputFile& operator=(const InputFile&) = delete;

    /// Replaces the file's contents with the input; returns its path.
    const std::string& write(const std::uint8_t* data, std::size_t size) {
        std::FILE* f = std::fopen(path_.c_str(), "wb");
        if (!f || (size > 0 && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) {
            std::perror(path_.c_str());  // the harness's own failure: stop, do not report inputs
            std::exit(2);
        }
        return path_;
    }

private:
    std::string path_;
};

/// Longest message a reader may put on the user's error line: a path, the
/// problem and a few numbers, never a whole input or a library's dump.
inline constexpr std::size_t kMaxMessageLength = 512;

/// The rules for an error a user sees: one line, of bounded length.
/// Breaking them is a finding like a crash (abort, so libFuzzer saves the input).
inline void checkUserMessage(const char* what) {
    const std::size_t length = std::strlen(what);
    const bool oneLine = std::strchr(what, '\n') == nullptr && std::strchr(what, '\r') == nullptr;
    if (oneLine && length <= kMaxMessageLength && length > 0) return;
    std::fprintf(stderr, "terrain fuzz: error message breaks the rules (%zu chars%s): %.200s\n", length,
                 oneLine ? "" : ", several lines", what);
    std::abort();
}

/// A property of a successful read that must hold: a finding when it does not.
inline void require(bool holds, const char* property) {
    if (holds) return;
    std::fprintf(stderr, "terrain fuzz: property broken: %s\n", property);
    std::abort();
}

/// Runs a reader on the input: success and terrain::Error are expected,
/// anything else (another exception, a crash, a sanitizer report) is not.
template <class Read>
void expectSuccessOrError(Read&& read) {
    try {
        read();
    } catch (const terrain::Error& e) {
        checkUserMessage(e.what());
    }
}

}  // namespace terrain::fuzz
