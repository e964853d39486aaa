// Fuzz target: comma-separated number lists of the command line (core/parse
// parseNumberList), and formatNumber, whose text of any parsed number must
// parse back to one number (messages quote numbers as it writes them).
#include <vector>

#include "core/parse.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    std::vector<float> values;
    terrain::fuzz::expectSuccessOrError([&] { values = terrain::parseNumberList(text, "--list"); });
    for (float v : values) {
        bool parsesBack = false;
        try {
            parsesBack = terrain::parseNumberList(terrain::formatNumber(v), "--list").size() == 1;
        } catch (const terrain::Error&) {}
        terrain::fuzz::require(parsesBack, "formatNumber's text of a parsed number parses back to one number");
    }
    return 0;
}
