#pragma once
// Small text parsers for command-line values.
#include <string>
#include <vector>

namespace terrain {

/// Parses a comma-separated list of numbers ("1,0.5,2"); throws InputError
/// naming `option` and the offending item when one is not a finite number
/// (nan, inf, or out of a float's range).
std::vector<float> parseNumberList(const std::string& text, const std::string& option);

/// A number as people write it in messages ("%g": 0.02, 25, 1e+06).
std::string formatNumber(double v);

}  // namespace terrain
