#pragma once
// Reading the engine's OpenVDB files without OpenVDB's reader, which trusts
// the file: corrupt files crash it, and sizes it reads make it allocate
// gigabytes. The engine writes a small, known layout (sim/vdb_io.h), so this
// reader parses exactly that layout (OpenVDB file format 222 to 224, as
// written by io::File: grid offsets, 32-bit Tree_float_5_4_3 grids, scale
// transforms, raw, zlib or Blosc blocks, with or without mask compression)
// from the file's bytes, checking every count, size and offset against the
// file before using it, and rejects anything else with one line.
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid.h"
#include "sim/vdb_tree.h"

namespace terrain::vdb {

/// A grid's entry in the file's table of grids.
struct GridEntry {
    std::string name;  // as written, less OpenVDB's suffix for repeated names
    std::string type;  // e.g. Tree_float_5_4_3
    bool instance = false;
    std::uint64_t gridPos = 0, blockPos = 0, endPos = 0;
};

/// A float grid up to its values: what a reader checks before allocating.
struct FloatGrid {
    std::string name;    // printable and short, for messages
    int declaredNx = 0;  // the engine's terrain_nx / terrain_ny metadata, 0 when absent
    int declaredNy = 0;
    double voxelX = 1.0, voxelY = 1.0;
    std::uint32_t compression = 0;
    Topology topology;
    std::uint64_t blockPos = 0, endPos = 0;
};

class FileReader {
public:
    /// Reads the file and its header and grid table (IoError when it is not
    /// an OpenVDB file of a supported version, or the table does not fit).
    explicit FileReader(const std::string& file);

    const std::vector<GridEntry>& grids() const { return grids_; }
    /// The first grid named `name`, or nullptr.
    const GridEntry* find(const std::string& name) const;
    /// The first 32-bit float grid, or nullptr.
    const GridEntry* firstFloatGrid() const;

    /// Reads a float grid's compression, metadata, transform and topology.
    FloatGrid readGrid(const GridEntry& entry) const;
    /// Reads the grid's values at z = 0 within nx x ny into out.
    void readValues(const FloatGrid& grid, int nx, int ny, Grid& out) const;

private:
    std::string file_;
    std::string bytes_;
    std::vector<GridEntry> grids_;
};

}  // namespace terrain::vdb
