// A frame's named layers (sim/frame_layers.h).
#include "sim/frame_layers.h"

#include <utility>

#include "sim/hydrology.h"
#include "sim/scene.h"

namespace terrain {

std::vector<std::string> FrameLayers::names() const {
    std::vector<std::string> out;
    out.reserve(layers.size());
    for (const FrameLayer& l : layers) out.push_back(l.name);
    return out;
}

std::vector<const Grid*> FrameLayers::grids() const {
    std::vector<const Grid*> out;
    out.reserve(layers.size());
    for (const FrameLayer& l : layers) out.push_back(&l.grid);
    return out;
}

const FrameLayer* FrameLayers::find(const std::string& name) const {
    for (const FrameLayer& l : layers)
        if (l.name == name) return &l;
    return nullptr;
}

FrameLayers stateLayers(const TerrainState& s) {
    FrameLayers f;
    f.cellSize = s.cellSize;
    Grid height;
    s.groundHeight(height);
    f.layers.push_back({"height", "m", std::move(height)});
    f.layers.push_back({"bedrock", "m", s.bedrock});
    f.layers.push_back({"soil", "m", s.soil});
    if (!s.water.empty()) f.layers.push_back({"water", "m", s.water});
    if (!s.suspended.empty()) f.layers.push_back({"sediment", "m", s.suspended});
    return f;
}

FrameLayers frameLayers(const Simulation& sim) {
    const TerrainState& s = sim.state();
    FrameLayers f = stateLayers(s);
    auto add = [&](const char* name, const char* unit, auto&& fill) {
        FrameLayer l{name, unit, Grid{}};
        fill(l.grid);
        f.layers.push_back(std::move(l));
    };
    if (hasWaterFlow(s)) {
        FrameLayer discharge{"discharge", "m^3/s", Grid{}};
        dischargeMap(s, discharge.grid);
        Grid sedimentFlux;  // carried by that discharge
        if (!s.suspended.empty()) sedimentFluxMap(s, discharge.grid, sedimentFlux);
        f.layers.push_back(std::move(discharge));
        add("velocity", "m/s", [&](Grid& g) { velocityMap(s, g); });
        if (!s.suspended.empty()) f.layers.push_back({"sediment_flux", "m^3/s", std::move(sedimentFlux)});
    }
    const HydrologyAccumulator& h = sim.hydrology();
    if (h.tracksGround()) {
        add("erosion", "m", [&](Grid& g) { h.erosionMap(g); });
        add("deposition", "m", [&](Grid& g) { h.depositionMap(g); });
        add("net_erosion", "m", [&](Grid& g) { h.netErosionMap(g); });
    }
    if (h.tracksWater()) add("wetness", "1", [&](Grid& g) { h.wetnessMap(g); });
    return f;
}

}  // namespace terrain
