#pragma once
// The light options every command that lights a terrain shares (`gi`,
// `render`, `demo`): the same flags set the same fields of a LightSet
// (sim/scene_lights.h) as a scene file's [lights] table, over it.
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "sim/scene_lights.h"

namespace terrain::app {

struct LightOptions {
    std::optional<std::string> environment;  // --light uniform | sunsky | env:FILE | FILE.exr / FILE.hdr
    std::optional<float> intensity;          // --light-intensity
    std::optional<float> visibility;         // --visibility (m, haze)
    std::vector<std::string> keys;           // --key AZ,EL,RADIUS,R,G,B (repeatable) or none
    std::optional<std::string> sun;          // --sun HOUR[,HOURS_PER_FRAME[,LATITUDE[,DAY]]] or off
};

/// Adds --light, --light-intensity, --key and --sun; `defaults` says where
/// unset values come from (e.g. "the scene").
void addLightOptions(CLI::App* sub, LightOptions& o, const std::string& defaults);

/// Sets what the options give over `lights` (--key replaces every key
/// light) and validates the result. Throws InputError naming the option.
void applyLightOptions(const LightOptions& o, LightSet& lights);

/// The options on their own, before a scene is read: applied to a set with
/// no lights, they must give a valid one. Throws InputError naming the option.
void checkLightOptions(const LightOptions& o);

}  // namespace terrain::app
