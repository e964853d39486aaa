// core/parse: number lists of the command line and quoting input in messages.
#include <string>

#include <doctest/doctest.h>

#include "core/error.h"
#include "core/parse.h"

using namespace terrain;

namespace {
// The message parseNumberList throws for text, or "" when it parses.
std::string numberListError(const std::string& text) {
    try {
        parseNumberList(text, "--key");
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}
}  // namespace

TEST_CASE("core.parse: number lists") {
    CHECK(parseNumberList("1,0.5,-2e3", "--key") == std::vector<float>{1.0f, 0.5f, -2000.0f});
    CHECK(parseNumberList("", "--key").empty());
    CHECK(numberListError("1,x,3") == "--key '1,x,3': 'x' is not a number");
    CHECK(numberListError("1,2.5q") == "--key '1,2.5q': '2.5q' is not a number");
    CHECK(numberListError("1,,2") == "--key '1,,2': '' is not a number");
}

TEST_CASE("core.parse: a bad number list's message is one short line, whatever the text") {
    // found by the fuzz target number_list: the message quoted the whole text,
    // line breaks included
    const std::string withBreak = numberListError("4=,1\n9");
    CHECK(withBreak == "--key '4=,1\\x0a9': '4=' is not a number");
    const std::string huge = numberListError("1," + std::string(5000, '7') + "x");
    CHECK(huge.size() < 200);
    CHECK(huge.find('\n') == std::string::npos);
}

TEST_CASE("core.parse: quoteForMessage") {
    CHECK(quoteForMessage("river.png") == "'river.png'");
    CHECK(quoteForMessage("") == "''");
    CHECK(quoteForMessage("a\tb\r\n\x7f\xc3") == "'a\\x09b\\x0d\\x0a\\x7f\\xc3'");
    const std::string cut = quoteForMessage(std::string(kMaxQuotedChars, 'a') + "b");
    CHECK(cut == "'" + std::string(kMaxQuotedChars, 'a') + "...'");
    CHECK(quoteForMessage(std::string(kMaxQuotedChars, 'a')) == "'" + std::string(kMaxQuotedChars, 'a') + "'");
    // the limit holds for the escaped form: 60 control bytes show as 15 escapes
    // (found by the fuzz target: escapes had made the message 4 times as long)
    const std::string escapes = quoteForMessage(std::string(kMaxQuotedChars, '\x1e'));
    CHECK(escapes.size() == kMaxQuotedChars + 5);
    CHECK(escapes.substr(0, 9) == "'\\x1e\\x1e");
}
