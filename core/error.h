#pragma once
// Typed exceptions for the boundaries (files, scene files, CLI, GL context).
// main() turns any of them into one line on stderr and a non-zero exit.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace terrain {

/// Base of every error the engine reports to a user.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A file could not be read or written, or its contents are wrong.
class IoError : public Error {
public:
    IoError(const std::string& file, const std::string& what) : Error(file + ": " + what), file_(file) {}
    const std::string& file() const { return file_; }

private:
    std::string file_;
};

/// A parameter or input value is out of range (NaN heights, absurd sizes...).
class InputError : public Error {
public:
    using Error::Error;
};

/// A third-party message fit for one line of ours: line breaks become
/// spaces, and beyond `max` characters it is cut short with "...".
inline std::string oneLine(std::string_view text, std::size_t max = 200) {
    std::string s(text.substr(0, max));
    for (char& c : s)
        if (c == '\n' || c == '\r') c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return text.size() > max ? s + "..." : s;
}

}  // namespace terrain
