// gi(): one `terrain gi` run on a numpy height array. The keyword options
// are the command's flags (bounces=2 is --bounces 2), parsed by the flags'
// own CLI11 definitions (app/gi_options.h), so names, defaults, ranges and
// messages are the command's, and the frame runs through the same code.
#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/gi_options.h"
#include "app/gi_run.h"
#include "python/bindings.h"
#include "python/numpy_grids.h"
#include "sim/heightmap_io.h"

namespace terrain::python {
namespace {

// The flags the keyword options stand for: out_shade="a.exr" is
// --out-shade=a.exr, key=[...] a --key per item, a bool --flag=true|false.
std::vector<std::string> flagsOf(const py::kwargs& options) {
    std::vector<std::string> args;
    for (const auto& [key, value] : options) {
        std::string name = py::str(key);
        if (name == "heightmap" || name == "z_scale" || name == "z_offset")
            throw py::value_error("gi(): '" + name +
                                  "' is about the command's input file; pass the heights as an array (in metres)");
        std::replace(name.begin(), name.end(), '_', '-');
        const auto flag = [&](const py::handle& v) {
            const std::string text =
                py::isinstance<py::bool_>(v) ? (v.cast<bool>() ? "true" : "false") : std::string(py::str(v));
            args.push_back("--" + name + "=" + text);
        };
        if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value))
            for (const py::handle& item : value) flag(item);
        else
            flag(value);
    }
    return args;
}

app::GiOptions parseOptions(const py::kwargs& options, double cellSize) {
    app::GiOptions o;
    CLI::App cli("gi");
    app::addGiOptions(&cli, o);
    std::vector<std::string> args = flagsOf(options);
    std::reverse(args.begin(), args.end());  // CLI11 takes a vector last argument first
    try {
        cli.parse(args);
    } catch (const CLI::ParseError& e) {
        throw py::value_error(std::string("gi(): ") + e.what());
    }
    o.heightmap = "the height array";
    o.cellSize = cellSize;
    o.progress = false;
    return o;
}

py::dict runGi(const py::object& heights, double cellSize, const py::kwargs& options) {
    if (!(cellSize > 0.0)) throw py::value_error("gi(): cell_size must be > 0 (metres between grid points)");
    const app::GiOptions o = parseOptions(options, cellSize);
    app::checkGiOptions(o);
    app::ExponentSource exponent;
    const gi::GiSettings settings = app::giSettingsFrom(o, exponent);
    Grid grid = gridFromArray(heights, "gi(): heights", kMinHeightmapSide);
    const app::GiInputs in = app::giInputsFor(o, exponent, std::move(grid), 0.0f, GeoReference{});
    app::GiMaps maps;
    {
        py::gil_scoped_release unlocked;  // the frame runs on TBB's threads and touches no Python object
        maps = app::runGiFrames(o, settings, in);
        app::writeGiMaps(o, in, maps);
    }
    py::dict out;
    out["shade"] = interleaveRgb(maps.shade);
    out["ambient"] = adoptGrid(std::move(maps.ambient));
    if (maps.hasIndirect) out["indirect"] = interleaveRgb(maps.indirect);
    return out;
}

}  // namespace

void addGi(py::module_& m) {
    m.def("gi", &runGi, py::arg("heights"), py::arg("cell_size"),
          R"(Lights a height field as `terrain gi` does and returns its maps.

heights: float32 array (rows, columns) of heights in metres (any strides;
    TypeError for another dtype, ValueError for NaN or Inf, another number
    of dimensions or a side under 2).
cell_size: metres between grid points.
options: the flags of `terrain gi`, '-' written '_': light="sunsky",
    key=["135,30,3,1,0.95,0.9"] (a list for a repeated flag), bounces=2,
    subsample=2, threads=2, indirect_kernel="blocker", brdf="mix:0.3,40",
    reference=True, out_ambient="a.npy", ... (`terrain gi --help` lists
    them). out_shade, out_ambient and out_indirect write the same files as
    the command. A wrong option raises ValueError with the command's message.

Returns a dict of new float32 arrays: "shade" (rows, columns, 3; direct
plus indirect light, what --out-shade writes), "ambient" (rows, columns)
and, with bounces or the reference's indirect light, "indirect" (rows,
columns, 3). The GIL is released while the frame runs; the result is the
same for any thread count.)");
}

}  // namespace terrain::python
