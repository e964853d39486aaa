// TOML scene files (toml++). A scene file may start from a built-in scene
// and set anything a built-in sets; unknown keys and wrong types are errors,
// so a typo never silently does nothing.
//
//   name = "my-bay"
//   base = "waves"            # optional: start from a built-in
//   size = 300                # or [nx, ny]
//   cell_size = 1.5           # m
//   seed = 7
//   dt = 0.0                  # s, 0 = derived from the CFL limits
//   spin_up = 0.0             # s simulated before an animation's first frame
//   change_tile = 32
//   soil_depth = 2.0          # m
//   water_level = 0.0         # m, fill water up to this level
//   [terrain]  kind = "noise" | "shape" | "dem", plus the generator's keys
//   [hydraulic] enabled = true, ...   [thermal] ...   [waves] ...
//   [waves.swell] ...   [[waves.drops]] ...
//   [gi] incremental = true, tolerance = 0.01, refresh = 0   # change-driven GI frames
//   [materials.bedrock] albedo = [r, g, b], exponent = 10     # sim/materials.h; likewise
//   [materials.soil] ... cover_depth   [materials.vegetation] ... min_altitude, max_altitude,
//   altitude_fade, max_slope   [materials.snow] ... line, altitude_fade, max_slope
//   [materials.wet] darkening, depth, exponent   [materials.water] albedo, exponent, clarity
//   [materials.foam] enabled, albedo, exponent, max_depth, min_gradient
//   [lights] environment = "uniform" | "sunsky" | "sky.exr", intensity = 1.0,   # sim/scene_lights.h
//            visibility = 400000.0   # m, haze (0: clear)
//   [lights.sky] zenith, horizon, ground = [r, g, b]      # the sunsky model's colours
//   [[lights.key]] azimuth, elevation, radius, rgb         # replaces the base scene's key lights
//   [lights.sun] latitude, day, hour, hours_per_frame, north, radius, rgb
//   [camera] fov = 40   [[camera.key]] frame, yaw, pitch, distance, target = [x, y(, z)]   # sim/scene_camera.h
#include <array>
#include <cmath>
#include <filesystem>
#include <set>

#include <toml++/toml.h>

#include "core/error.h"
#include "sim/scene.h"

namespace terrain {
namespace {

// Reads keys from one TOML table, remembering which were used.
class TableReader {
public:
    TableReader(const toml::table& t, std::string file, std::string path)
        : t_(t), file_(std::move(file)), path_(std::move(path)) {}

    void num(const char* key, float& out) {
        if (const toml::node* n = get(key)) {
            if (auto v = n->value<double>())
                out = static_cast<float>(*v);
            else
                fail(key, "a number");
            if (!std::isfinite(out)) fail(key, "a finite number");
        }
    }
    void num(const char* key, double& out) {
        if (const toml::node* n = get(key)) {
            if (auto v = n->value<double>())
                out = *v;
            else
                fail(key, "a number");
        }
    }
    void rgb(const char* key, std::array<float, 3>& out) {
        if (const toml::node* n = get(key)) {
            const toml::array* a = n->as_array();
            if (!a || a->size() != 3) fail(key, "an array of three numbers [r, g, b]");
            for (std::size_t c = 0; c < 3; ++c) {
                auto v = a->get(c)->value<double>();
                if (!v || !std::isfinite(*v)) fail(key, "an array of three numbers [r, g, b]");
                out[c] = static_cast<float>(*v);
            }
        }
    }
    void integer(const char* key, int& out) {
        if (const toml::node* n = get(key)) {
            if (auto v = n->value<std::int64_t>())
                out = static_cast<int>(*v);
            else
                fail(key, "an integer");
        }
    }
    void flag(const char* key, bool& out) {
        if (const toml::node* n = get(key)) {
            if (auto v = n->value<bool>())
                out = *v;
            else
                fail(key, "true or false");
        }
    }
    void text(const char* key, std::string& out) {
        if (const toml::node* n = get(key)) {
            if (auto v = n->value<std::string>())
                out = *v;
            else
                fail(key, "a string");
        }
    }
    const toml::node* get(const char* key) {
        used_.insert(key);
        return t_.get(key);
    }
    const toml::table* table(const char* key) {
        if (const toml::node* n = get(key)) {
            if (const toml::table* tt = n->as_table()) return tt;
            fail(key, "a table");
        }
        return nullptr;
    }
    [[noreturn]] void fail(const std::string& key, const std::string& expected) const {
        throw IoError(file_, "'" + path_ + key + "' must be " + expected);
    }
    void finish() const {
        for (auto&& [k, v] : t_) {
            (void)v;
            if (!used_.count(std::string(k.str())))
                throw IoError(file_, "unknown key '" + path_ + std::string(k.str()) + "'");
        }
    }
    const std::string& file() const { return file_; }

private:
    const toml::table& t_;
    std::string file_;
    std::string path_;
    std::set<std::string> used_;
};

int parseEdge(const std::string& file, const std::string& e) {
    if (e == "-x") return 0;
    if (e == "+x") return 1;
    if (e == "-y") return 2;
    if (e == "+y") return 3;
    throw IoError(file, "'waves.swell.edge' must be one of -x, +x, -y, +y (got '" + e + "')");
}

// A path in a scene file is relative to the file.
std::string besideFile(const std::string& file, const std::string& path) {
    std::filesystem::path p(path);
    if (p.is_relative()) p = std::filesystem::path(file).parent_path() / p;
    return p.string();
}

void readTerrain(TableReader& r, const toml::table& t, SceneSettings& s) {
    TableReader tr(t, r.file(), "terrain.");
    std::string kind;
    tr.text("kind", kind);
    if (!kind.empty()) {
        if (kind == "noise")
            s.terrain.kind = TerrainSource::Kind::Noise;
        else if (kind == "shape")
            s.terrain.kind = TerrainSource::Kind::Shape;
        else if (kind == "dem")
            s.terrain.kind = TerrainSource::Kind::Dem;
        else
            tr.fail("kind", "\"noise\", \"shape\" or \"dem\"");
    }
    NoiseSettings& n = s.terrain.noise;
    tr.num("amplitude", n.amplitude);
    tr.num("wavelength", n.wavelength);
    tr.integer("octaves", n.octaves);
    tr.num("lacunarity", n.lacunarity);
    tr.num("gain", n.gain);
    tr.flag("ridged", n.ridged);
    tr.num("offset", n.offset);
    ShapeSettings& sh = s.terrain.shape;
    std::string shape;
    tr.text("shape", shape);
    if (!shape.empty()) {
        try {
            sh.shape = parseShape(shape);
        } catch (const InputError& e) {
            throw IoError(r.file(), std::string("terrain.shape: ") + e.what());
        }
    }
    tr.num("base", sh.base);
    tr.num("height", sh.height);
    tr.num("radius", sh.radius);
    tr.num("ridge_wavelength", sh.wavelength);
    tr.num("angle", sh.angleDeg);
    std::string file;
    tr.text("file", file);
    if (!file.empty()) s.terrain.demFile = besideFile(r.file(), file);
    tr.num("z_scale", s.terrain.demZScale);
    tr.num("z_offset", s.terrain.demZOffset);
    tr.num("cell_size", s.terrain.demCellSize);
    tr.flag("resample", s.terrain.demResample);
    tr.num("ramp_start", s.terrain.rampStart);
    tr.num("ramp_end", s.terrain.rampEnd);
    tr.finish();
}

void readHydraulic(const std::string& file, const toml::table& t, SceneSettings& s) {
    TableReader r(t, file, "hydraulic.");
    HydraulicSettings& h = s.hydraulicSettings;
    r.flag("enabled", s.hydraulic);
    r.num("gravity", h.gravity);
    r.num("pipe_area", h.pipeArea);
    r.num("rain_rate", h.rainRate);
    r.num("capacity", h.capacity);
    r.num("dissolve", h.dissolve);
    r.num("deposit", h.deposit);
    r.num("evaporation", h.evaporation);
    r.num("min_tilt", h.minTilt);
    r.num("bedrock_hardness", h.bedrockHardness);
    r.num("max_erosion_depth", h.maxErosionDepth);
    r.flag("closed_boundary", h.closedBoundary);
    r.finish();
}

void readThermal(const std::string& file, const toml::table& t, SceneSettings& s) {
    TableReader r(t, file, "thermal.");
    r.flag("enabled", s.thermal);
    r.num("talus_deg", s.thermalSettings.talusAngleDeg);
    r.num("rate", s.thermalSettings.rate);
    r.flag("erode_bedrock", s.thermalSettings.erodeBedrock);
    r.finish();
}

void readWaves(const std::string& file, const toml::table& t, SceneSettings& s) {
    TableReader r(t, file, "waves.");
    WaveSettings& w = s.waveSettings;
    r.flag("enabled", s.waves);
    r.num("gravity", w.gravity);
    r.num("courant", w.courant);
    r.num("max_courant", w.maxCourant);
    r.num("dry_depth", w.dryDepth);
    r.num("friction", w.friction);
    r.flag("advection", w.advection);
    if (const toml::table* sw = r.table("swell")) {
        TableReader q(*sw, file, "waves.swell.");
        w.swell.enabled = true;
        q.flag("enabled", w.swell.enabled);
        std::string edge;
        q.text("edge", edge);
        if (!edge.empty()) w.swell.edge = parseEdge(file, edge);
        q.num("amplitude", w.swell.amplitude);
        q.num("period", w.swell.period);
        w.swell.seaLevel = s.waterLevel;  // default: the scene's water level
        q.num("sea_level", w.swell.seaLevel);
        q.num("ramp_periods", w.swell.rampPeriods);
        q.finish();
    }
    if (const toml::node* d = r.get("drops")) {
        const toml::array* arr = d->as_array();
        if (!arr) r.fail("drops", "an array of tables ([[waves.drops]])");
        w.drops.clear();
        for (const toml::node& item : *arr) {
            const toml::table* dt = item.as_table();
            if (!dt) r.fail("drops", "an array of tables ([[waves.drops]])");
            TableReader q(*dt, file, "waves.drops.");
            WaveDrop drop;
            q.num("time", drop.time);
            q.num("x", drop.x);
            q.num("y", drop.y);
            q.num("radius", drop.radius);
            q.num("height", drop.height);
            q.finish();
            w.drops.push_back(drop);
        }
    }
    r.finish();
}

void readMaterial(TableReader& r, Material& m) {
    r.rgb("albedo", m.albedo);
    r.num("exponent", m.phongExponent);
}

// A rule's table switches it on unless it says `enabled = false`.
void readMaterials(const std::string& file, const toml::table& t, MaterialSet& m) {
    TableReader r(t, file, "materials.");
    if (const toml::table* b = r.table("bedrock")) {
        TableReader q(*b, file, "materials.bedrock.");
        readMaterial(q, m.bedrock);
        q.finish();
    }
    if (const toml::table* b = r.table("soil")) {
        TableReader q(*b, file, "materials.soil.");
        readMaterial(q, m.soil.material);
        q.num("cover_depth", m.soil.coverDepth);
        q.finish();
    }
    if (const toml::table* b = r.table("vegetation")) {
        TableReader q(*b, file, "materials.vegetation.");
        VegetationRule& v = m.vegetation;
        v.enabled = true;
        q.flag("enabled", v.enabled);
        readMaterial(q, v.material);
        q.num("min_altitude", v.minAltitude);
        q.num("max_altitude", v.maxAltitude);
        q.num("altitude_fade", v.altitudeFade);
        q.num("max_slope", v.maxSlopeDeg);
        q.finish();
    }
    if (const toml::table* b = r.table("snow")) {
        TableReader q(*b, file, "materials.snow.");
        SnowRule& v = m.snow;
        v.enabled = true;
        q.flag("enabled", v.enabled);
        readMaterial(q, v.material);
        q.num("line", v.line);
        q.num("altitude_fade", v.altitudeFade);
        q.num("max_slope", v.maxSlopeDeg);
        q.finish();
    }
    if (const toml::table* b = r.table("wet")) {
        TableReader q(*b, file, "materials.wet.");
        q.num("darkening", m.wet.darkening);
        q.num("depth", m.wet.depth);
        q.num("exponent", m.wet.phongExponent);
        q.finish();
    }
    if (const toml::table* b = r.table("water")) {
        TableReader q(*b, file, "materials.water.");
        readMaterial(q, m.water.material);
        q.num("clarity", m.water.clarity);
        q.finish();
    }
    if (const toml::table* b = r.table("foam")) {
        TableReader q(*b, file, "materials.foam.");
        m.foam.enabled = true;
        q.flag("enabled", m.foam.enabled);
        readMaterial(q, m.foam.material);
        q.num("max_depth", m.foam.maxDepth);
        q.num("min_gradient", m.foam.minDepthGradient);
        q.finish();
    }
    r.finish();
    try {
        validateMaterials(m);
    } catch (const InputError& e) {
        throw IoError(file, e.what());
    }
}

void readEnvironment(TableReader& r, const std::string& file, EnvironmentSpec& e) {
    std::string kind;
    r.text("environment", kind);
    if (kind == "uniform") {
        e.kind = EnvironmentSpec::Kind::Uniform;
    } else if (kind == "sunsky") {
        e.kind = EnvironmentSpec::Kind::SunSky;
    } else if (!kind.empty()) {
        const std::string ext = std::filesystem::path(kind).extension().string();
        if (ext != ".exr" && ext != ".hdr") r.fail("environment", "\"uniform\", \"sunsky\" or an .exr / .hdr image");
        e.kind = EnvironmentSpec::Kind::Image;
        e.file = besideFile(file, kind);
    }
    r.num("intensity", e.intensity);
    r.num("visibility", e.visibility);
    if (const toml::table* t = r.table("sky")) {
        TableReader q(*t, file, "lights.sky.");
        q.rgb("zenith", e.zenith);
        q.rgb("horizon", e.horizon);
        q.rgb("ground", e.ground);
        q.finish();
    }
}

// [[lights.key]] tables replace the base scene's key lights.
void readKeys(TableReader& r, const std::string& file, std::vector<KeyLightSpec>& keys) {
    const toml::node* n = r.get("key");
    if (!n) return;
    const toml::array* arr = n->as_array();
    if (!arr) r.fail("key", "an array of tables ([[lights.key]])");
    keys.clear();
    for (const toml::node& item : *arr) {
        const toml::table* t = item.as_table();
        if (!t) r.fail("key", "an array of tables ([[lights.key]])");
        TableReader q(*t, file, "lights.key.");
        KeyLightSpec k;
        q.num("azimuth", k.azimuthDeg);
        q.num("elevation", k.elevationDeg);
        q.num("radius", k.radiusDeg);
        q.rgb("rgb", k.rgb);
        q.finish();
        keys.push_back(k);
    }
}

void readSun(const toml::table& t, const std::string& file, SunSpec& sun) {
    TableReader q(t, file, "lights.sun.");
    sun.enabled = true;
    q.flag("enabled", sun.enabled);
    q.num("latitude", sun.latitudeDeg);
    q.integer("day", sun.dayOfYear);
    q.num("hour", sun.hour);
    q.num("hours_per_frame", sun.hoursPerFrame);
    q.num("north", sun.northAzimuthDeg);
    q.num("radius", sun.radiusDeg);
    q.rgb("rgb", sun.rgb);
    q.finish();
}

void readLights(const std::string& file, const toml::table& t, LightSet& lights) {
    TableReader r(t, file, "lights.");
    readEnvironment(r, file, lights.environment);
    readKeys(r, file, lights.keys);
    if (const toml::table* sun = r.table("sun")) readSun(*sun, file, lights.sun);
    r.finish();
    try {
        validateLights(lights);
    } catch (const InputError& e) {
        throw IoError(file, e.what());
    }
}

void readCamera(const std::string& file, const toml::table& t, CameraPath& path) {
    TableReader r(t, file, "camera.");
    r.num("fov", path.fovYDeg);
    if (const toml::node* n = r.get("key")) {
        const toml::array* arr = n->as_array();
        if (!arr) r.fail("key", "an array of tables ([[camera.key]])");
        path.keys.clear();
        for (const toml::node& item : *arr) {
            const toml::table* kt = item.as_table();
            if (!kt) r.fail("key", "an array of tables ([[camera.key]])");
            TableReader q(*kt, file, "camera.key.");
            CameraKey k;
            q.num("frame", k.frame);
            q.num("yaw", k.yawDeg);
            q.num("pitch", k.pitchDeg);
            q.num("distance", k.distance);
            if (const toml::node* tn = q.get("target")) {
                const toml::array* a = tn->as_array();
                bool numbers = a && (a->size() == 2 || a->size() == 3);
                for (std::size_t j = 0; numbers && j < a->size(); ++j) numbers = a->get(j)->value<double>().has_value();
                if (!numbers) q.fail("target", "[x, y] or [x, y, z], fractions of the extent (z: of the relief)");
                for (std::size_t j = 0; j < a->size(); ++j)
                    k.target[j] = static_cast<float>(*a->get(j)->value<double>());
            }
            q.finish();
            path.keys.push_back(k);
        }
    }
    r.finish();
    try {
        validateCameraPath(path);
    } catch (const InputError& e) {
        throw IoError(file, e.what());
    }
}

void readGi(const std::string& file, const toml::table& t, SceneSettings& s) {
    TableReader r(t, file, "gi.");
    if (r.get("incremental")) {
        bool on = true;
        r.flag("incremental", on);
        s.gi.incremental = on;
    }
    if (r.get("tolerance")) {
        float tolerance = 0.0f;
        r.num("tolerance", tolerance);
        if (tolerance < 0.0f) r.fail("tolerance", "a number >= 0");
        s.gi.tolerance = tolerance;
    }
    if (r.get("refresh")) {
        int every = 0;
        r.integer("refresh", every);
        s.gi.refreshEvery = every;
    }
    r.finish();
}

}  // namespace

SceneSettings loadSceneFile(const std::string& file) {
    if (!std::filesystem::exists(file)) throw IoError(file, "cannot open: no such file");
    toml::table root;
    try {
        root = toml::parse_file(file);
    } catch (const toml::parse_error& e) {
        const auto& b = e.source().begin;
        throw IoError(file, "TOML syntax error at line " + std::to_string(b.line) + ", column " +
                                std::to_string(b.column) + ": " + std::string(e.description()));
    }
    TableReader r(root, file, "");
    std::string base;
    r.text("base", base);
    int nx = 256, ny = 256;
    if (const toml::node* sz = r.get("size")) {
        if (auto v = sz->value<std::int64_t>())
            nx = ny = static_cast<int>(*v);
        else if (const toml::array* a = sz->as_array();
                 a && a->size() == 2 && a->get(0)->is_integer() && a->get(1)->is_integer()) {
            nx = static_cast<int>(*a->get(0)->value<std::int64_t>());
            ny = static_cast<int>(*a->get(1)->value<std::int64_t>());
        } else {
            r.fail("size", "an integer or [nx, ny]");
        }
    }
    SceneSettings s;
    if (!base.empty()) {
        try {
            s = builtinScene(base, std::max(nx, ny), 1);
        } catch (const InputError& e) {
            throw IoError(file, std::string("base: ") + e.what());
        }
    } else {
        s.terrain.kind = TerrainSource::Kind::Noise;
    }
    s.nx = nx;
    s.ny = ny;
    s.name = std::filesystem::path(file).stem().string();
    r.text("name", s.name);
    r.num("cell_size", s.cellSize);
    int seed = static_cast<int>(s.seed);
    r.integer("seed", seed);
    s.seed = static_cast<std::uint64_t>(seed);
    r.num("dt", s.dt);
    r.num("spin_up", s.spinUp);
    if (!(s.spinUp >= 0.0f) || s.spinUp > 1.0e6f) r.fail("spin_up", "a time in [0, 1e6] s");
    r.integer("change_tile", s.changeTile);
    r.num("soil_depth", s.soilDepth);
    if (r.get("water_level")) {
        s.hasWaterLevel = true;
        r.num("water_level", s.waterLevel);
    }
    if (const toml::table* t = r.table("terrain")) readTerrain(r, *t, s);
    if (const toml::table* t = r.table("hydraulic")) readHydraulic(file, *t, s);
    if (const toml::table* t = r.table("thermal")) readThermal(file, *t, s);
    if (const toml::table* t = r.table("waves")) readWaves(file, *t, s);
    if (const toml::table* t = r.table("gi")) readGi(file, *t, s);
    if (const toml::table* t = r.table("materials")) readMaterials(file, *t, s.materials);
    if (const toml::table* t = r.table("lights")) readLights(file, *t, s.lights);
    if (const toml::table* t = r.table("camera")) readCamera(file, *t, s.camera);
    r.finish();
    try {
        checkDimensions(s.nx, s.ny, s.cellSize);
    } catch (const InputError& e) {
        throw IoError(file, e.what());
    }
    return s;
}

}  // namespace terrain
