#pragma once
// A one-line progress bar on stdout (only when stdout is a terminal, or when
// TERRAIN_PROGRESS=1; stderr carries errors only), and the checks that an
// output folder or file can be written.
#include <cstdio>
#include <string>

namespace terrain::app {

class Progress {
public:
    Progress(std::string label, long long total, bool enabled);
    void update(long long done);
    void clear();
    void finish();

private:
    std::string label_;
    long long total_;
    bool enabled_;
    int lastPercent_ = -1;
    double start_;
};

/// Creates the folder if needed and checks a file can be written in it;
/// throws IoError naming the folder otherwise.
void ensureWritableDirectory(const std::string& dir);

/// Checks, before any work, that `file` can be written: its folder exists
/// and is writable, and it is not a folder itself. Throws IoError naming it.
void checkWritableFile(const std::string& file);

}  // namespace terrain::app
