#pragma once
// A one-line progress bar on stderr (only when stderr is a terminal, or when
// TERRAIN_PROGRESS=1), and the check that an output folder is writable.
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

}  // namespace terrain::app
