// OpenVDB read/write of terrain layers, kept in one translation unit because
// the OpenVDB headers are expensive to compile .
//
// Layout: each layer is a 2-D openvdb::FloatGrid, voxel (x, y, 0) = cell
// (x, y), background 0, with a uniform linear transform whose voxel size is
// the cell size. Grids: `height` (bedrock + soil), `bedrock`, `soil`, and
// `water`, `sediment` when the terrain has them.
#include "sim/vdb_io.h"

#include <cmath>
#include <filesystem>
#include <mutex>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "core/error.h"
#include "core/file_io.h"

namespace terrain {
namespace {

void initVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

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

void fromVdb(const std::string& file, const openvdb::FloatGrid& grid, int nx, int ny, Grid& out) {
    out.resize(nx, ny);
    auto acc = grid.getConstAccessor();
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) {
            const float v = acc.getValue(openvdb::Coord(x, y, 0));
            if (!std::isfinite(v))
                throw IoError(file, "grid '" + grid.getName() + "' has a non-finite value at x=" + std::to_string(x) +
                                        ", y=" + std::to_string(y));
            out(x, y) = v;
        }
}

}  // namespace

void writeVdb(const std::string& file, const TerrainState& s) {
    initVdb();
    openvdb::GridPtrVec grids;
    Grid height;
    s.groundHeight(height);
    grids.push_back(toVdb(height, "height", s.cellSize));
    grids.push_back(toVdb(s.bedrock, "bedrock", s.cellSize));
    grids.push_back(toVdb(s.soil, "soil", s.cellSize));
    if (!s.water.empty()) grids.push_back(toVdb(s.water, "water", s.cellSize));
    if (!s.suspended.empty()) grids.push_back(toVdb(s.suspended, "sediment", s.cellSize));
    const std::string tmp = temporaryNameFor(file);
    try {
        openvdb::io::File out(tmp);
        out.setCompression(openvdb::io::COMPRESS_BLOSC);
        out.write(grids);
        out.close();
    } catch (const openvdb::Exception& e) {
        std::remove(tmp.c_str());
        throw IoError(file, std::string("OpenVDB write failed: ") + e.what());
    }
    commitTemporary(tmp, file);
}

void readVdb(const std::string& file, TerrainState& s, const LayerSet& layers) {
    initVdb();
    if (!std::filesystem::exists(file)) throw IoError(file, "cannot open: no such file");
    openvdb::GridPtrVecPtr grids;
    try {
        openvdb::io::File in(file);
        in.open();
        grids = in.getGrids();
        in.close();
    } catch (const std::exception& e) {
        throw IoError(file, std::string("corrupt, truncated or not an OpenVDB file: ") + e.what());
    }
    if (!grids || grids->empty()) throw IoError(file, "contains no grids");
    auto find = [&](const std::string& name) -> openvdb::FloatGrid::Ptr {
        for (auto& g : *grids)
            if (g->getName() == name) {
                auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
                if (!f) throw IoError(file, "grid '" + name + "' is a " + g->valueType() + " grid, not a float grid");
                return f;
            }
        return nullptr;
    };
    openvdb::FloatGrid::Ptr bedrock = find("bedrock");
    openvdb::FloatGrid::Ptr soil = find("soil");
    openvdb::FloatGrid::Ptr height = find("height");
    if (!height && !bedrock) {
        for (auto& g : *grids)
            if ((height = openvdb::gridPtrCast<openvdb::FloatGrid>(g))) break;
        if (!height) throw IoError(file, "has no float grid (expected one named 'height')");
    }
    const openvdb::FloatGrid& ref = bedrock ? *bedrock : *height;
    // size from our metadata, or else from the active bounding box
    int nx = 0, ny = 0;
    const openvdb::CoordBBox box = ref.evalActiveVoxelBoundingBox();
    if (auto m = ref.getMetadata<openvdb::Int32Metadata>("terrain_nx")) nx = m->value();
    if (auto m = ref.getMetadata<openvdb::Int32Metadata>("terrain_ny")) ny = m->value();
    if (nx == 0 || ny == 0) {
        if (box.empty()) throw IoError(file, "grid '" + ref.getName() + "' has no active voxels");
        if (box.min().x() != 0 || box.min().y() != 0)
            throw IoError(file, "grid '" + ref.getName() + "' does not start at voxel (0, 0)");
        nx = box.max().x() + 1;
        ny = box.max().y() + 1;
    }
    if (!box.empty() && (box.min().z() != 0 || box.max().z() != 0))
        throw IoError(file, "grid '" + ref.getName() + "' is 3-D; a height field is one z layer");
    const openvdb::Vec3d vs = ref.voxelSize();
    if (!ref.transform().isLinear() || std::abs(vs.x() - vs.y()) > 1e-6 * vs.x())
        throw IoError(file, "grid '" + ref.getName() + "' has non-uniform or non-linear voxels");
    try {
        checkDimensions(nx, ny, static_cast<float>(vs.x()));
    } catch (const InputError& e) {
        throw IoError(file, e.what());
    }
    s.allocate(nx, ny, static_cast<float>(vs.x()), layers);
    if (bedrock) {
        fromVdb(file, *bedrock, nx, ny, s.bedrock);
        if (soil) fromVdb(file, *soil, nx, ny, s.soil);
    } else {
        fromVdb(file, *height, nx, ny, s.bedrock);
    }
    if (!s.water.empty())
        if (auto w = find("water")) fromVdb(file, *w, nx, ny, s.water);
    if (!s.suspended.empty())
        if (auto sd = find("sediment")) fromVdb(file, *sd, nx, ny, s.suspended);
}

}  // namespace terrain
