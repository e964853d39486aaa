// Scenes and the simulation: what `terrain sim` runs, stepped from Python,
// its layers seen as numpy arrays over the engine's own storage.
#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/stl.h>

#include "app/option_ranges.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/setting_range.h"
#include "python/bindings.h"
#include "python/numpy_grids.h"
#include "sim/frame_layers.h"
#include "sim/scene.h"
#include "sim/scene_ranges.h"
#include "sim/vdb_io.h"

namespace terrain::python {
namespace {

// Every layer a terrain can carry, in the order layers() lists them.
std::vector<std::pair<const char*, Grid TerrainState::*>> layerTable() {
    return {{"bedrock", &TerrainState::bedrock},     {"soil", &TerrainState::soil},   {"water", &TerrainState::water},
            {"suspended", &TerrainState::suspended}, {"fluxL", &TerrainState::fluxL}, {"fluxR", &TerrainState::fluxR},
            {"fluxT", &TerrainState::fluxT},         {"fluxB", &TerrainState::fluxB}, {"velX", &TerrainState::velX},
            {"velY", &TerrainState::velY},           {"faceU", &TerrainState::faceU}, {"faceV", &TerrainState::faceV}};
}

std::vector<std::string> allocatedLayers(const TerrainState& s) {
    std::vector<std::string> names;
    for (const auto& [name, member] : layerTable())
        if (!(s.*member).empty()) names.emplace_back(name);
    return names;
}

std::string joined(const std::vector<std::string>& names) {
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

py::array layerView(const py::object& self, const std::string& name) {
    const Simulation& sim = self.cast<const Simulation&>();
    const TerrainState& s = sim.state();
    std::vector<std::string> every;
    for (const auto& [layer, member] : layerTable()) {
        every.emplace_back(layer);
        if (name != layer) continue;
        if ((s.*member).empty())
            throw py::value_error("layer '" + name + "' is not allocated in scene '" + sim.settings().name +
                                  "' (it has: " + joined(allocatedLayers(s)) + ")");
        return readOnlyView(s.*member, self);
    }
    throw py::value_error("no layer '" + name + "' (layers: " + joined(every) + ")");
}

// The scene `terrain sim --scene nameOrFile [--size] [--seed] [--dt]` runs,
// the overrides checked as the command checks its flags.
SceneSettings resolved(const std::string& nameOrFile, std::optional<int> size, std::optional<std::int64_t> seed,
                       std::optional<double> dt) {
    SceneOverrides over;
    if (size) checkRange(scene_ranges::kSize, *size, "size");
    if (seed) checkRange(scene_ranges::kSeed, *seed, "seed");
    if (dt) checkRange(widened(scene_ranges::kDt), *dt, "dt");
    over.size = size;
    if (seed) over.seed = static_cast<std::uint64_t>(*seed);
    if (dt) over.dt = static_cast<float>(*dt);
    return resolveScene(nameOrFile, over);
}

// As `terrain sim`: no NaN or Inf leaves the simulation.
void checkDiverged(const TerrainState& s) {
    try {
        checkFinite(s);
    } catch (const InputError& e) {
        throw InputError("the simulation diverged by tick " + std::to_string(s.tick) + ": " + e.what());
    }
}

void tick(Simulation& sim, std::int64_t n, int threads) {
    if (n < 0) throw py::value_error("tick(n): n must be >= 0 (got " + std::to_string(n) + ")");
    checkRange(app::option_ranges::kThreads, threads, "threads");
    py::gil_scoped_release unlocked;  // the ticks run on TBB's threads and touch no Python object
    withThreads(threads, [&] {
        for (std::int64_t t = 0; t < n; ++t) sim.tick();
        return 0;
    });
    checkDiverged(sim.state());
}

void addScene(py::module_& m) {
    py::class_<SceneSettings>(m, "Scene",
                              "A scene: its grid, the stages it runs and its time step (sim/scene.h). Made by "
                              "builtin_scene() or load_scene(); read-only.")
        .def_property_readonly(
            "name", [](const SceneSettings& s) { return s.name; }, "The scene's name")
        .def_property_readonly(
            "nx", [](const SceneSettings& s) { return s.nx; }, "Columns (x)")
        .def_property_readonly(
            "ny", [](const SceneSettings& s) { return s.ny; }, "Rows (y)")
        .def_property_readonly(
            "cell_size", [](const SceneSettings& s) { return s.cellSize; }, "Metres between grid points")
        .def_property_readonly(
            "seed", [](const SceneSettings& s) { return s.seed; }, "The terrain's noise seed")
        .def_property_readonly(
            "stages",
            [](const SceneSettings& s) {
                std::vector<std::string> st;
                if (s.hydraulic) st.emplace_back("hydraulic");
                if (s.thermal) st.emplace_back("thermal");
                if (s.waves) st.emplace_back("waves");
                return st;
            },
            "The simulators the scene runs, in order")
        .def("__repr__", [](const SceneSettings& s) {
            return "<terrain.Scene '" + s.name + "' " + std::to_string(s.nx) + " x " + std::to_string(s.ny) + ">";
        });
    m.def(
        "builtin_scene",
        [](const std::string& name, int size, std::int64_t seed) {
            const std::vector<std::string> names = builtinSceneNames();
            if (std::find(names.begin(), names.end(), name) == names.end())
                throw py::value_error("no built-in scene '" + name + "' (built-in: " + joined(names) + ")");
            return resolved(name, size, seed, std::nullopt);
        },
        py::arg("name"), py::arg("size") = 256, py::arg("seed") = 1,
        "A built-in scene (erosion, waves, dem) of size x size cells: the scene of `terrain sim --scene NAME "
        "--size SIZE --seed SEED`. ValueError for an unknown name or a value out of range.");
    m.def(
        "load_scene",
        [](const std::string& path, std::optional<int> size, std::optional<std::int64_t> seed,
           std::optional<double> dt) {
            if (path.size() <= 5 || path.substr(path.size() - 5) != ".toml")
                throw py::value_error("load_scene: a scene file ends in .toml (got '" + path + "')");
            return resolved(path, size, seed, dt);
        },
        py::arg("path"), py::arg("size") = py::none(), py::arg("seed") = py::none(), py::arg("dt") = py::none(),
        "A TOML scene file, with what `terrain sim --scene PATH` sets over it: size (the grid side; the extent "
        "is kept), seed, dt (s; 0 = from the CFL limits). OSError when the file cannot be read, ValueError for "
        "a wrong value.");
}

}  // namespace

void addSimulation(py::module_& m) {
    addScene(m);
    py::class_<Simulation>(m, "Simulation",
                           "A running simulation of a scene: the terrain state and the fixed-step tick "
                           "(sim/scene.h). One thread at a time may use a Simulation.")
        .def(py::init<const SceneSettings&>(), py::arg("scene"),
             "Builds the scene's initial terrain (reading its DEM, if any).")
        .def("tick", &tick, py::arg("n") = 1, py::arg("threads") = 0,
             "Advances n fixed time steps on `threads` worker threads (0: all cores; the result is the same for "
             "any count). The GIL is released meanwhile. ValueError if the state diverges (NaN or Inf).")
        .def_property_readonly(
            "time", [](const Simulation& s) { return s.state().time; }, "Simulated time, s")
        .def_property_readonly(
            "tick_count", [](const Simulation& s) { return s.state().tick; }, "Ticks run so far")
        .def_property_readonly(
            "dt", [](const Simulation& s) { return s.dt(); }, "The fixed time step, s")
        .def_property_readonly(
            "scene", [](const Simulation& s) { return s.settings(); }, "The scene (a copy)")
        .def(
            "state_hash", [](const Simulation& s) { return hashHex(hashState(s.state())); },
            "The state's hash, 16 hex digits: what `terrain sim --hash-every` prints after as many ticks")
        .def("layer", &layerView, py::arg("name"),
             "Layer `name` as a read-only float32 array of shape (rows, columns), C order, over the "
             "simulation's own storage (no copy; the array keeps the Simulation alive). tick() updates it in "
             "place, except faceU and faceV, which the wave solver swaps with its scratch every sub-step: take "
             "those again after ticking. Copy (np.array(layer)) to keep or change values. ValueError for an "
             "unknown or unallocated layer.")
        .def(
            "layers",
            [](const py::object& self) {
                py::dict out;
                for (const std::string& name : allocatedLayers(self.cast<const Simulation&>().state()))
                    out[py::str(name)] = layerView(self, name);
                return out;
            },
            "Every allocated layer by name, as layer() gives it: bedrock and soil, and as the scene's stages need "
            "them water, suspended, fluxL, fluxR, fluxT, fluxB, velX, velY, faceU ((rows, columns + 1)) and "
            "faceV ((rows + 1, columns)).")
        .def(
            "ground",
            [](const Simulation& s) {
                Grid h;
                s.state().groundHeight(h);
                return adoptGrid(std::move(h));
            },
            "A new float32 array of the ground height, bedrock + soil (m), shape (rows, columns)")
        .def(
            "frame_layers",
            [](const Simulation& s) {
                py::dict out;
                for (FrameLayer& layer : frameLayers(s).layers)
                    out[py::str(layer.name)] = adoptGrid(std::move(layer.grid));
                return out;
            },
            "The layers a frame file holds, by name, in the frame writers' order, as new float32 arrays of shape "
            "(rows, columns): height, bedrock, soil, water, sediment and the hydrology maps the scene has "
            "(discharge, velocity, sediment_flux, erosion, deposition, net_erosion, wetness; README, \"Frame "
            "layers\").")
        .def(
            "write_vdb",
            [](const Simulation& s, const std::string& path) {
                checkDiverged(s.state());
                writeVdbLayers(path, frameLayers(s));
            },
            py::arg("path"),
            "Writes the frame's layers (frame_layers()) to an OpenVDB file, as `terrain sim --format vdb` writes a "
            "frame");
}

}  // namespace terrain::python
