#pragma once
// The tree of one OpenVDB FloatGrid (Tree_float_5_4_3: a root table of
// 4096³ internal nodes, 128³ internal nodes below them, 8³ leaves) read
// from a file without OpenVDB: the topology first (which nodes exist, which
// voxels are active), so a caller can check the layout and size before
// allocating, then the values of the z = 0 layer into a grid.
#include <cstdint>
#include <vector>

#include "core/byte_reader.h"
#include "core/grid.h"

namespace terrain::vdb {

/// A leaf: its origin (a multiple of 8) and its active mask (512 bits, in
/// the file's bytes).
struct Leaf {
    std::int32_t x, y, z;
    const unsigned char* activeMask;
};

/// An inactive tile crossing the z = 0 layer whose value is not the
/// background: it fills its square of that layer.
struct Tile {
    std::int32_t x, y;
    std::int32_t side;
    float value;
};

/// Active voxels of a tree: how many, and the box holding them.
struct ActiveVoxels {
    std::int64_t count = 0;
    std::int64_t minX = 0, minY = 0, maxX = -1, maxY = -1;
};

struct Topology {
    float background = 0.0f;
    std::vector<Leaf> leaves;  // in the order of their value blocks
    std::vector<Tile> tiles;
    ActiveVoxels active;
};

/// Reads a tree's topology (buffer count, root, internal nodes, leaf masks)
/// from r. IoError (naming `grid`) when the layout is malformed or the tree
/// is not a height field: an active tile, or an active voxel off z = 0.
Topology readTopology(ByteReader& r, std::uint32_t compression, const std::string& grid);

/// Reads the leaves' value blocks that follow the topology and writes the
/// values of the z = 0 layer within nx x ny into out (resized; cells no leaf
/// or tile covers hold the background), as OpenVDB's getValue would read them.
void readLayerValues(ByteReader& r, std::uint32_t compression, const Topology& t, int nx, int ny, Grid& out);

}  // namespace terrain::vdb
