#pragma once
// Small text parsers for command-line values.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace terrain {

/// Parses a comma-separated list of numbers ("1,0.5,2"); throws InputError
/// naming `option` and the offending item when one is not a finite number
/// (nan, inf, or out of a float's range).
std::vector<float> parseNumberList(const std::string& text, const std::string& option);

/// A number as people write it in messages ("%g": 0.02, 25, 1e+06).
std::string formatNumber(double v);
/// Text from an input (a command-line value, a line of a file) as a message
/// quotes it: in single quotes, bytes outside printable ASCII as \xNN, cut
/// with "..." where the quoted form would pass kMaxQuotedChars characters, so
/// that the message stays one short line whatever the input holds.
std::string quoteForMessage(std::string_view text);
inline constexpr std::size_t kMaxQuotedChars = 60;

}  // namespace terrain
