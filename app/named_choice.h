#pragma once
// A flag whose value is one of a few words, each naming a setting: the one
// place that turns the word into the setting or into the flag's error line.
#include <initializer_list>
#include <string>
#include <utility>

#include "core/error.h"

namespace terrain::app {

/// The value `word` names among `choices`; otherwise InputError
/// "FLAG must be a, b or c (got 'word')", the names in the order given.
template <class E>
E namedChoice(const std::string& flag, const std::string& word,
              std::initializer_list<std::pair<const char*, E>> choices) {
    std::string names;
    std::size_t i = 0;
    for (const auto& [name, value] : choices) {
        if (word == name) return value;
        if (i > 0) names += i + 1 == choices.size() ? " or " : ", ";
        names += name;
        ++i;
    }
    throw InputError(flag + " must be " + names + " (got '" + word + "')");
}

}  // namespace terrain::app
