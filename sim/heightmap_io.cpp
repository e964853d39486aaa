// Heightmaps by file extension: greyscale PNG, GeoTIFF, float EXR or OpenVDB.
#include "sim/heightmap_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "core/image_io.h"
#include "core/png_io.h"
#include "sim/vdb_io.h"

namespace terrain {
namespace {

Grid readPng(const std::string& file, float zScale, float zOffset) {
    int bitDepth = 16;
    Grid g = readPngHeightmap(file, zScale, zOffset, &bitDepth);
    if (bitDepth < 16)
        std::fprintf(stderr,
                     "terrain: warning: %s is a %d-bit PNG: at most 256 height levels, so slopes show as terraces "
                     "(a 16-bit greyscale PNG keeps 65536)\n",
                     file.c_str(), bitDepth);
    return g;
}

Grid readVdbHeights(const std::string& file, float* cellSizeOut) {
    TerrainState s;
    readVdb(file, s, LayerSet{});
    if (cellSizeOut) *cellSizeOut = s.cellSize;
    Grid g;
    s.groundHeight(g);
    return g;
}

Grid readGeoTiff(const std::string& file, float* cellSizeOut, GeoReference* geoOut) {
    GeoTiffHeights tiff = readGeoTiffHeights(file);
    if (tiff.nodataFilled > 0)
        std::fprintf(stderr, "terrain: warning: %s: %lld nodata cells filled with the nearest valid height\n",
                     file.c_str(), static_cast<long long>(tiff.nodataFilled));
    if (cellSizeOut) *cellSizeOut = static_cast<float>(tiff.cellSize);
    if (geoOut) *geoOut = tiff.geo;
    return std::move(tiff.heights);
}

// The channel named `height`, else the file's only channel (Y, R, ...): a
// file of several other channels has no one height.
Grid readExrHeights(const std::string& file, float* cellSizeOut) {
    ExrChannels exr = readExrChannels(file, "height");
    if (exr.grids.empty() && exr.available.size() == 1) exr = readExrChannels(file, exr.available[0]);
    if (exr.grids.empty()) {
        std::string list;
        for (const std::string& n : exr.available) list += (list.empty() ? "" : ", ") + n;
        throw IoError(file, "EXR has no 'height' channel and more than one other (" + list +
                                "); a heightmap EXR has a channel named height or a single channel");
    }
    // a hostile attribute (NaN, Inf, negative) counts as none: the cell size is then given as for a PNG
    if (cellSizeOut && std::isfinite(exr.cellSize) && exr.cellSize > 0.0f) *cellSizeOut = exr.cellSize;
    return std::move(exr.grids[0]);
}

}  // namespace

Grid readHeightmap(const std::string& file, float zScale, float zOffset, float* cellSizeOut, GeoReference* geoOut) {
    const std::string ext = std::filesystem::path(file).extension().string();
    std::string lower = ext;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    Grid g;
    if (lower == ".png")
        g = readPng(file, zScale, zOffset);
    else if (lower == ".tif" || lower == ".tiff")
        g = readGeoTiff(file, cellSizeOut, geoOut);
    else if (lower == ".vdb")
        g = readVdbHeights(file, cellSizeOut);
    else if (lower == ".exr")
        g = readExrHeights(file, cellSizeOut);
    else
        throw IoError(file, "unknown heightmap format '" + ext + "' (use .png, .tif, .exr or .vdb)");
    if (g.nx < kMinHeightmapSide || g.ny < kMinHeightmapSide)
        throw IoError(file, "heightmap of " + std::to_string(g.nx) + " x " + std::to_string(g.ny) +
                                " cells; a heightmap needs at least " + std::to_string(kMinHeightmapSide) + " x " +
                                std::to_string(kMinHeightmapSide));
    // the readers reject non-finite values; bedrock + soil can still overflow
    for (std::size_t i = 0; i < g.v.size(); ++i)
        if (!std::isfinite(g.v[i]))
            throw IoError(file, "cell (" + std::to_string(i % g.nx) + ", " + std::to_string(i / g.nx) +
                                    ") has a non-finite height");
    return g;
}

}  // namespace terrain
