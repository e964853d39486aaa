// Heightmaps by file extension: 16-bit PNG or OpenVDB.
#include "sim/heightmap_io.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/error.h"
#include "core/png_io.h"
#include "sim/vdb_io.h"

namespace terrain {

Grid readHeightmap(const std::string& file, float zScale, float zOffset, float* cellSizeOut) {
    const std::string ext = std::filesystem::path(file).extension().string();
    std::string lower = ext;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    if (lower == ".png") return readPngHeightmap(file, zScale, zOffset);
    if (lower == ".vdb") {
        TerrainState s;
        readVdb(file, s, LayerSet{});
        if (cellSizeOut) *cellSizeOut = s.cellSize;
        Grid g;
        s.groundHeight(g);
        return g;
    }
    throw IoError(file, "unknown heightmap format '" + ext + "' (use .png or .vdb)");
}

}  // namespace terrain
