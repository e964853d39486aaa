#pragma once
// Checked, atomic file writes and whole-file reads.
//
// Every writer writes to a temporary name beside the target, checks that
// every byte reached the disk (stdio reports a full disk only when a buffer
// is flushed, often at close; the kernel may report it only at fsync), and
// renames the temporary into place only then. A failure removes the
// temporary and throws IoError: the target keeps its previous contents and
// no short file is ever put in its place.
#include <cstdio>
#include <string>
#include <string_view>

namespace terrain {

/// A temporary file beside `target`, open for writing through stream().
/// commit() closes it checked (closeWrittenFile) and renames it onto
/// `target`; destroyed without a successful commit, it removes the temporary.
class AtomicFile {
public:
    explicit AtomicFile(std::string target);  // IoError when it cannot be created
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::FILE* stream() const { return stream_; }
    void commit();

private:
    std::string target_;
    std::string temporary_;
    std::FILE* stream_ = nullptr;
    bool committed_ = false;
};

/// Writes bytes to `file` atomically (AtomicFile).
void writeFileAtomic(const std::string& file, std::string_view bytes);

/// Flushes, syncs and closes `f` (closed in every case), throwing IoError
/// naming `file` when any write to it failed (a full disk, a file size limit,
/// an I/O error).
void closeWrittenFile(std::FILE* f, const std::string& file);

/// Returns a temporary name beside `file`, for a writer that must open the
/// file by name itself (an external program).
std::string temporaryNameFor(const std::string& file);

/// Renames tmp onto file, removing tmp and throwing IoError on failure.
void commitTemporary(const std::string& tmp, const std::string& file);

/// The whole contents of `file` (IoError naming it when it cannot be read).
std::string readFileBytes(const std::string& file);

}  // namespace terrain
