// Small text parsers for command-line values.
#include "core/parse.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.h"

namespace terrain {

std::vector<float> parseNumberList(const std::string& text, const std::string& option) {
    std::vector<float> v;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        try {
            std::size_t used = 0;
            v.push_back(std::stof(item, &used));
            if (used != item.size()) throw std::invalid_argument(item);
        } catch (const std::exception&) {
            throw InputError(option + " " + quoteForMessage(text) + ": " + quoteForMessage(item) + " is not a number");
        }
    }
    return v;
}

std::string formatNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

std::string quoteForMessage(std::string_view text) {
    std::string out = "'";
    std::size_t shown = 0;
    for (char c : text) {
        if (shown == kMaxQuotedChars) {
            out += "...";
            break;
        }
        const auto byte = static_cast<unsigned char>(c);
        if (byte >= 0x20 && byte < 0x7f) {
            out += c;
        } else {
            char hex[5];
            std::snprintf(hex, sizeof hex, "\\x%02x", byte);
            out += hex;
        }
        ++shown;
    }
    return out + "'";
}

}  // namespace terrain
