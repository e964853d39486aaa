#pragma once
// Typed exceptions for the boundaries (files, scene files, CLI, GL context).
// main() turns any of them into one line on stderr and a non-zero exit.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace terrain {

/// The most bytes of detail an IoError carries after its file name. Details
/// can quote a hostile file (a grid name, a header line) or a third-party
/// library's message; a user's error stays one short line whatever they hold.
inline constexpr std::size_t kMaxErrorDetail = 200;

/// text as one bounded line for an error message: line breaks and tabs
/// become spaces, other control characters '?', and text over maxBytes is cut (at a UTF-8
/// character boundary) and ends in "...".
std::string boundedLine(std::string_view text, std::size_t maxBytes = kMaxErrorDetail);

/// Base of every error the engine reports to a user.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A file could not be read or written, or its contents are wrong. The
/// detail is bounded (boundedLine).
class IoError : public Error {
public:
    IoError(const std::string& file, std::string_view what) : Error(file + ": " + boundedLine(what)), file_(file) {}
    const std::string& file() const { return file_; }

private:
    std::string file_;
};

/// A parameter or input value is out of range (NaN heights, absurd sizes...).
class InputError : public Error {
public:
    using Error::Error;
};

}  // namespace terrain
