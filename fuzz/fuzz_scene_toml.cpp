// Fuzz target: TOML scene files (sim/scene_file.cpp loadSceneFile). Only the
// reading and validation: the terrain is not generated.
#include "fuzz/fuzz_input.h"
#include "sim/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static terrain::fuzz::InputFile file(".toml");
    const std::string& path = file.write(data, size);
    terrain::fuzz::expectSuccessOrError([&] {
        const terrain::SceneSettings s = terrain::loadSceneFile(path);
        terrain::fuzz::require(s.nx > 0 && s.ny > 0, "a scene that loads has a positive size");
    });
    return 0;
}
