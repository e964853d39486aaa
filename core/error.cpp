// Bounded error text: a message quoting a file or a library stays one short line.
#include "core/error.h"

namespace terrain {

std::string boundedLine(std::string_view text, std::size_t maxBytes) {
    const std::string_view ellipsis = "...";
    std::string out;
    if (text.size() <= maxBytes) {
        out = text;
    } else {
        std::size_t keep = maxBytes > ellipsis.size() ? maxBytes - ellipsis.size() : 0;
        // never cut a UTF-8 character: back up while the first byte dropped continues one
        while (keep > 0 && (static_cast<unsigned char>(text[keep]) & 0xC0) == 0x80) --keep;
        out = std::string(text.substr(0, keep)) + std::string(ellipsis);
    }
    for (char& c : out) {
        if (c == '\n' || c == '\r' || c == '\t')
            c = ' ';
        else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F)
            c = '?';
    }
    return out;
}

}  // namespace terrain
