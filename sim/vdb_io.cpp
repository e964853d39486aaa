// OpenVDB frames of the terrain's layers. Writing goes through OpenVDB (the
// OpenVDB headers stay in this translation unit: they are expensive to
// compile); reading parses the engine's own layout (sim/vdb_read.h).
//
// Layout: each layer is a 2-D openvdb::FloatGrid, voxel (x, y, 0) = cell
// (x, y), every cell active, background 0, with a uniform linear transform
// whose voxel size is the cell size, and int32 metadata terrain_nx and
// terrain_ny. Grids: a frame's layers in order (sim/frame_layers.h): `height`
// (bedrock + soil), `bedrock`, `soil`, `water` and `sediment` when the
// terrain has them, then a simulation's hydrology maps. Blosc-compressed.
#include "sim/vdb_io.h"

#include <cmath>
#include <mutex>
#include <sstream>

#include <openvdb/io/Archive.h>
#include <openvdb/openvdb.h>

#include "core/error.h"
#include "core/file_io.h"
#include "core/size_limits.h"
#include "sim/vdb_read.h"

namespace terrain {
namespace {

void initVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

// io::File::write streams into an std::ofstream whose failures it never
// checks, so a full disk gave a short file and no error. This writes the
// bytes io::File writes (its header, with grid offsets) into memory instead;
// writeFileAtomic then puts them on disk with every step checked.
class MemoryArchive : public openvdb::io::Archive {
public:
    std::string encode(const openvdb::GridPtrVec& grids) const {
        std::ostringstream out(std::ios_base::binary);
        Archive::write(out, grids, /*seekable=*/true);
        return std::move(out).str();
    }
};

openvdb::FloatGrid::Ptr toVdb(const Grid& g, const std::string& name, float cellSize) {
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(name);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(static_cast<double>(cellSize)));
    grid->setGridClass(openvdb::GRID_UNKNOWN);
    auto acc = grid->getAccessor();
    for (int y = 0; y < g.ny; ++y)
        for (int x = 0; x < g.nx; ++x) acc.setValueOn(openvdb::Coord(x, y, 0), g(x, y));
    grid->insertMeta("terrain_nx", openvdb::Int32Metadata(g.nx));
    grid->insertMeta("terrain_ny", openvdb::Int32Metadata(g.ny));
    return grid;
}

// The size of the reference layer. Its active voxels must fill exactly
// nx x ny cells at z = 0 from (0, 0), as writeVdb writes them; that also
// bounds what is allocated by what the file holds (a leaf's mask alone
// takes a byte per cell). The size is the engine's metadata when present,
// which must agree.
void layerSize(const std::string& file, const vdb::FloatGrid& g, int& nx, int& ny) {
    const vdb::ActiveVoxels& a = g.topology.active;
    if (a.count == 0) throw IoError(file, "grid '" + g.name + "' has no active voxels");
    if (a.minX != 0 || a.minY != 0) throw IoError(file, "grid '" + g.name + "' does not start at voxel (0, 0)");
    checkDeclaredSize(file, a.maxX + 1, a.maxY + 1, "cells");
    nx = static_cast<int>(a.maxX + 1);
    ny = static_cast<int>(a.maxY + 1);
    if ((g.declaredNx != 0 || g.declaredNy != 0) && (g.declaredNx != nx || g.declaredNy != ny))
        throw IoError(file, "grid '" + g.name + "' declares " + std::to_string(g.declaredNx) + " x " +
                                std::to_string(g.declaredNy) + " cells but its active voxels span " +
                                std::to_string(nx) + " x " + std::to_string(ny));
    if (a.count != std::int64_t{nx} * ny)
        throw IoError(file, "grid '" + g.name + "' has " + std::to_string(a.count) + " active voxels in its " +
                                std::to_string(nx) + " x " + std::to_string(ny) +
                                " box; a height field has one per cell");
}

float cellSizeOf(const std::string& file, const vdb::FloatGrid& g) {
    if (!(g.voxelX > 0.0) || std::abs(g.voxelX - g.voxelY) > 1e-6 * g.voxelX)
        throw IoError(file, "grid '" + g.name + "' has non-uniform or non-positive voxels");
    return static_cast<float>(g.voxelX);
}

void readLayer(const std::string& file, const vdb::FileReader& reader, const vdb::FloatGrid& g, int nx, int ny,
               Grid& out) {
    reader.readValues(g, nx, ny, out);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
            if (!std::isfinite(out(x, y)))
                throw IoError(file, "grid '" + g.name + "' has a non-finite value at x=" + std::to_string(x) +
                                        ", y=" + std::to_string(y));
}

}  // namespace

void writeVdb(const std::string& file, const TerrainState& s) { writeVdbLayers(file, stateLayers(s)); }

void writeVdbLayers(const std::string& file, const FrameLayers& frame) {
    initVdb();
    openvdb::GridPtrVec grids;
    for (const FrameLayer& layer : frame.layers) grids.push_back(toVdb(layer.grid, layer.name, frame.cellSize));
    std::string bytes;
    try {
        MemoryArchive archive;
        archive.setCompression(openvdb::io::COMPRESS_BLOSC);
        bytes = archive.encode(grids);
    } catch (const openvdb::Exception& e) {
        throw IoError(file, std::string("OpenVDB could not encode the frame: ") + e.what());
    }
    writeFileAtomic(file, bytes);
}

void readVdb(const std::string& file, TerrainState& s, const LayerSet& layers) {
    const vdb::FileReader reader(file);
    const vdb::GridEntry* bedrock = reader.find("bedrock");
    const vdb::GridEntry* height = reader.find("height");
    const vdb::GridEntry* base = bedrock ? bedrock : (height ? height : reader.firstFloatGrid());
    if (!base) throw IoError(file, "has no float grid (expected one named 'height')");
    const vdb::FloatGrid ref = reader.readGrid(*base);
    int nx = 0, ny = 0;
    layerSize(file, ref, nx, ny);
    const float cell = cellSizeOf(file, ref);
    try {
        checkDimensions(nx, ny, cell);
    } catch (const InputError& e) {
        throw IoError(file, e.what());
    }
    s.allocate(nx, ny, cell, layers);
    readLayer(file, reader, ref, nx, ny, s.bedrock);
    auto readOptional = [&](const char* name, Grid& out) {
        if (const vdb::GridEntry* e = reader.find(name)) readLayer(file, reader, reader.readGrid(*e), nx, ny, out);
    };
    if (bedrock) readOptional("soil", s.soil);
    if (!s.water.empty()) readOptional("water", s.water);
    if (!s.suspended.empty()) readOptional("sediment", s.suspended);
}

}  // namespace terrain
