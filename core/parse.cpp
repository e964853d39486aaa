// Small text parsers for command-line values.
#include "core/parse.h"

#include <cmath>
#include <cstdio>
#include <cstring>
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
        if (!std::isfinite(v.back()))
            throw InputError(option + " " + quoteForMessage(text) + ": " + quoteForMessage(item) + " is not finite");
    }
    return v;
}

std::string formatNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

std::string quoteForMessage(std::string_view text) {
    std::string quoted;
    for (char c : text) {
        const auto byte = static_cast<unsigned char>(c);
        char shown[5] = {c, 0};
        if (byte < 0x20 || byte >= 0x7f) std::snprintf(shown, sizeof shown, "\\x%02x", byte);
        if (quoted.size() + std::strlen(shown) > kMaxQuotedChars) {
            quoted += "...";
            break;
        }
        quoted += shown;
    }
    return "'" + quoted + "'";
}

}  // namespace terrain
