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
            throw InputError(option + " '" + boundedLine(text, 80) + "': '" + boundedLine(item, 40) +
                             "' is not a number");
        }
        if (!std::isfinite(v.back()))
            throw InputError(option + " '" + boundedLine(text, 80) + "': '" + boundedLine(item, 40) +
                             "' is not finite");
    }
    return v;
}

std::string formatNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

}  // namespace terrain
