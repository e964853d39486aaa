// The engine's readers and writers on numpy arrays: the files are those the
// command line writes (atomic, checked; OSError naming the file on failure).
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/stl.h>

#include "core/geotiff_io.h"
#include "core/image_io.h"
#include "core/png_io.h"
#include "core/size_limits.h"
#include "python/bindings.h"
#include "python/numpy_grids.h"
#include "sim/heightmap_io.h"

namespace terrain::python {
namespace {

// The dimensions of an array (0 for anything else, which checkedFloat32 refuses).
int dimsOf(const py::handle& object) {
    return py::isinstance<py::array>(object) ? static_cast<int>(py::reinterpret_borrow<py::array>(object).ndim()) : 0;
}

// A 2-D array, or a 3-D one as its planes (the last axis the channels).
std::vector<Grid> planes(const py::handle& object, const std::string& what) {
    const py::array any = checkedFloat32(object, dimsOf(object) == 3 ? 3 : 2, what);
    const py::ssize_t channels = any.ndim() == 3 ? any.shape(2) : 1;
    if (any.shape(0) < 1 || any.shape(1) < 1 || any.shape(0) > kMaxGridSide || any.shape(1) > kMaxGridSide ||
        channels < 1)
        throw py::value_error(what + ": empty or too large (each side 1 to " + std::to_string(kMaxGridSide) + ")");
    std::vector<Grid> out;
    for (py::ssize_t k = 0; k < channels; ++k) out.push_back(planeOf(any, k));
    return out;
}

void writeNpyFile(const std::string& path, const py::object& object) {
    const py::array a = checkedFloat32(object, dimsOf(object), "write_npy");
    // C order for the file: a view is copied (np.ascontiguousarray), the dtype kept
    const py::array c = py::module_::import("numpy").attr("ascontiguousarray")(a);
    std::vector<std::size_t> shape;
    for (py::ssize_t d = 0; d < c.ndim(); ++d) shape.push_back(static_cast<std::size_t>(c.shape(d)));
    writeNpyArray(path, shape, static_cast<const float*>(c.data()));
}

void writeExrFile(const std::string& path, const py::object& object) {
    const std::vector<Grid> g = planes(object, "write_exr");
    if (g.size() != 1 && g.size() != 3)
        throw py::value_error("write_exr: expected (rows, columns) or (rows, columns, 3), got " +
                              std::to_string(g.size()) + " channels");
    std::vector<const Grid*> channels;
    for (const Grid& c : g) channels.push_back(&c);
    writeExr(path, channels);
}

void writeGeoTiffFile(const std::string& path, const py::object& object, const std::array<double, 6>& transform,
                      const std::string& crsWkt) {
    const std::vector<Grid> bands = planes(object, "write_geotiff");
    GeoReference geo;
    geo.transform = transform;
    geo.crsWkt = crsWkt;
    writeGeoTiff(path, bands, geo);
}

std::pair<float, float> writePngHeights(const std::string& path, const py::object& object, std::optional<float> zScale,
                                        std::optional<float> zOffset) {
    const Grid h = gridFromArray(object, "write_png_heightmap");
    float scale = 1.0f, offset = 0.0f;
    pngRangeFor(h, scale, offset);
    if (zScale) scale = *zScale;
    if (zOffset) offset = *zOffset;
    if (!(scale > 0.0f)) throw py::value_error("write_png_heightmap: z_scale must be > 0");
    writePngHeightmap(path, h, scale, offset);
    return {scale, offset};
}

py::tuple readHeights(const std::string& path, float zScale, float zOffset) {
    float cell = 0.0f;
    Grid h = readHeightmap(path, zScale, zOffset, &cell);
    return py::make_tuple(adoptGrid(std::move(h)), cell > 0.0f ? py::cast(cell) : py::none());
}

}  // namespace

void addIo(py::module_& m) {
    m.def("write_npy", &writeNpyFile, py::arg("path"), py::arg("array"),
          "Writes a float32 array of any shape as a .npy file (the engine's writer, as --out-ambient x.npy).");
    m.def("write_exr", &writeExrFile, py::arg("path"), py::arg("array"),
          "Writes a float32 (rows, columns) array as a one-channel (Y) or a (rows, columns, 3) one as an RGB "
          "half-float OpenEXR, as `terrain gi` writes its .exr maps.");
    m.def("write_geotiff", &writeGeoTiffFile, py::arg("path"), py::arg("array"),
          py::arg("transform") = std::array<double, 6>{0.0, 1.0, 0.0, 0.0, 0.0, 1.0}, py::arg("crs_wkt") = "",
          "Writes a float32 (rows, columns) array as one band, or (rows, columns, k) as k bands, to a "
          "DEFLATE-compressed float32 GeoTIFF with GDAL's geotransform `transform` and the CRS `crs_wkt` (WKT; "
          "empty: not georeferenced), as `terrain gi` writes its .tif maps.");
    m.def("write_png_heightmap", &writePngHeights, py::arg("path"), py::arg("heights"), py::arg("z_scale") = py::none(),
          py::arg("z_offset") = py::none(),
          "Writes heights (float32, rows x columns, m) as a 16-bit greyscale PNG: value = round((h - z_offset) / "
          "z_scale), clamped to 0..65535; z_scale and z_offset default to the heights' range. Returns (z_scale, "
          "z_offset), the --z-scale and --z-offset that read it back.");
    m.def("read_heightmap", &readHeights, py::arg("path"), py::arg("z_scale") = 1.0f, py::arg("z_offset") = 0.0f,
          "Reads a heightmap as `terrain gi --heightmap` does: a 16-bit PNG (height = z_offset + z_scale * "
          "value), a GeoTIFF (metres, as stored) or a .vdb. Returns (heights, cell_size): a new float32 array "
          "(rows, columns) and the file's cell size in metres (None for a PNG). OSError when it cannot be read.");
}

}  // namespace terrain::python
