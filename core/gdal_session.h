#pragma once
// What every use of GDAL in core shares (not installed): the library set up
// once, quietly, and its error messages collected instead of printed, so a
// bad file gives the user one bounded line and nothing else on stderr.
#include <string>

namespace terrain::gdal {

/// Registers GDAL's drivers once per process and turns off what would read
/// or write files beside the one named (.aux.xml side-cars, directory scans).
void ensureRegistered();

/// While alive, GDAL's messages on this thread (its error handler stack is
/// per thread) are collected here instead of going to stderr: the first
/// failure's text is kept, warnings and debug output are dropped.
class ErrorCapture {
public:
    ErrorCapture();
    ~ErrorCapture();
    ErrorCapture(const ErrorCapture&) = delete;
    ErrorCapture& operator=(const ErrorCapture&) = delete;

    bool failed() const { return failed_; }
    /// The first failure's message, or `fallback` when GDAL gave none.
    std::string message(const std::string& fallback) const;

    /// Called by the handler GDAL calls; records a failure's message.
    static void handleFromGdal(int level, int code, const char* text, void* self);

private:
    bool failed_ = false;
    std::string first_;
};

}  // namespace terrain::gdal
