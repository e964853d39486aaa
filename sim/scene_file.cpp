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
#include <cstdint>
#include <filesystem>
#include <optional>
#include <set>
#include <span>
#include <system_error>

#include <toml++/toml.h>

#include "core/error.h"
#include "core/geotiff_io.h"
#include "sim/scene.h"
#include "sim/scene_ranges.h"

namespace terrain {
namespace {

namespace ranges = scene_ranges;

// The node as a 64-bit integer: an integer, or a float with an integral value
// (`size = 256.0`) that a 64-bit integer holds. toml++'s own float -> integer
// conversion casts first and checks after, which is undefined behaviour for a
// float beyond 2^63 (`seed = 3e83`).
std::optional<std::int64_t> integerOf(const toml::node& n) {
    if (const auto* i = n.as_integer()) return i->get();
    const auto* f = n.as_floating_point();
    if (!f) return std::nullopt;
    const double v = f->get();
    constexpr double kTwo63 = 9223372036854775808.0;
    if (!(v >= -kTwo63 && v < kTwo63) || v != std::trunc(v)) return std::nullopt;
    return static_cast<std::int64_t>(v);
}

// Reads keys from one TOML table, remembering which were used.
class TableReader {
public:
    TableReader(const toml::table& t, std::string file, std::string path)
        : t_(t), file_(std::move(file)), path_(std::move(path)) {}

    // A finite number; its range is checked by the table's validation
    // (materials, camera), which sees the values together.
    void num(const char* key, float& out) {
        if (const toml::node* n = get(key)) {
            out = static_cast<float>(finite(key, *n));
            if (!std::isfinite(out)) fail(key, "a finite number (as a float)");
        }
    }
    // A number in its declared range (sim/scene_ranges.h), checked before it
    // is narrowed to a float.
    void num(const char* key, float& out, const SettingRange<float>& range) {
        if (const toml::node* n = get(key)) {
            const double v = finite(key, *n);
            inRange(widened(range), v, key);
            out = static_cast<float>(v);
        }
    }
    void num(const char* key, double& out, const SettingRange<double>& range) {
        if (const toml::node* n = get(key)) {
            out = finite(key, *n);
            inRange(range, out, key);
        }
    }
    // An array of lo..hi finite numbers into the first entries of out.
    void numbers(const char* key, std::span<float> out, std::size_t lo, const std::string& expected) {
        if (const toml::node* n = get(key)) {
            const toml::array* a = n->as_array();
            if (!a || a->size() < lo || a->size() > out.size()) fail(key, expected);
            for (std::size_t c = 0; c < a->size(); ++c) {
                auto v = a->get(c)->value<double>();
                if (!v || !std::isfinite(*v)) fail(key, expected);
                out[c] = static_cast<float>(*v);
            }
        }
    }
    void rgb(const char* key, std::array<float, 3>& out) {
        numbers(key, out, 3, "an array of three numbers [r, g, b]");
    }
    // Each of r, g, b in the range.
    void rgb(const char* key, std::array<float, 3>& out, const SettingRange<float>& range) {
        std::array<float, 3> v = out;
        rgb(key, v);
        for (float c : v) inRange(range, c, key);
        out = v;
    }
    // An integer in its declared range, checked before it is narrowed.
    void integer(const char* key, int& out, const SettingRange<int>& range) {
        std::int64_t v = out;
        integer(key, v, widened(range));
        out = static_cast<int>(v);
    }
    void integer(const char* key, std::int64_t& out, const SettingRange<std::int64_t>& range) {
        if (const toml::node* n = get(key)) {
            if (auto v = integerOf(*n))
                out = *v;
            else
                fail(key, "an integer");
            inRange(range, out, key);
        }
    }
    // A grid side: the integer node n (the value of `key` or one of its
    // entries) in its range.
    int side(const char* key, const toml::node& n) const {
        const std::int64_t v = integerOf(n).value_or(0);
        inRange(widened(ranges::kSize), v, key);
        return static_cast<int>(v);
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
    // The table `key`, read by read(reader) and checked for unknown keys;
    // false when there is none.
    template <class Read>
    bool child(const char* key, Read&& read) {
        const toml::table* t = table(key);
        if (!t) return false;
        TableReader q(*t, file_, path_ + key + ".");
        read(q);
        q.finish();
        return true;
    }
    // Each table of the array of tables `key` ([[path.key]]), in order;
    // false when there is none.
    template <class Read>
    bool children(const char* key, Read&& read) {
        const toml::node* n = get(key);
        if (!n) return false;
        const std::string expected = "an array of tables ([[" + path_ + key + "]])";
        const toml::array* arr = n->as_array();
        if (!arr) fail(key, expected);
        for (const toml::node& item : *arr) {
            const toml::table* t = item.as_table();
            if (!t) fail(key, expected);
            TableReader q(*t, file_, path_ + key + ".");
            read(q);
            q.finish();
        }
        return true;
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
    double finite(const char* key, const toml::node& n) const {
        const std::optional<double> v = n.value<double>();
        if (!v) fail(key, "a number");
        if (!std::isfinite(*v)) fail(key, "a finite number");
        return *v;
    }
    // The range's check, as an error of this file naming the key.
    template <class T>
    void inRange(const SettingRange<T>& range, T v, const std::string& key) const {
        try {
            checkRange(range, v, "'" + path_ + key + "'");
        } catch (const InputError& e) {
            throw IoError(file_, e.what());
        }
    }

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

// Runs a check that throws InputError as an error of the scene file.
template <class Check>
void checkIn(const std::string& file, Check&& check) {
    try {
        check();
    } catch (const InputError& e) {
        throw IoError(file, e.what());
    }
}

void readTerrain(TableReader& r, SceneSettings& s) {
    std::string kind;
    r.text("kind", kind);
    if (!kind.empty()) {
        if (kind == "noise")
            s.terrain.kind = TerrainSource::Kind::Noise;
        else if (kind == "shape")
            s.terrain.kind = TerrainSource::Kind::Shape;
        else if (kind == "dem")
            s.terrain.kind = TerrainSource::Kind::Dem;
        else
            r.fail("kind", "\"noise\", \"shape\" or \"dem\"");
    }
    NoiseSettings& n = s.terrain.noise;
    r.num("amplitude", n.amplitude, ranges::kAltitude);
    r.num("wavelength", n.wavelength, ranges::kLength);
    r.integer("octaves", n.octaves, ranges::kOctaves);
    r.num("lacunarity", n.lacunarity, ranges::kLacunarity);
    r.num("gain", n.gain, ranges::kFraction);
    r.flag("ridged", n.ridged);
    r.num("offset", n.offset, ranges::kAltitude);
    ShapeSettings& sh = s.terrain.shape;
    std::string shape;
    r.text("shape", shape);
    if (!shape.empty()) {
        try {
            sh.shape = parseShape(shape);
        } catch (const InputError& e) {
            throw IoError(r.file(), std::string("terrain.shape: ") + e.what());
        }
    }
    r.num("base", sh.base, ranges::kAltitude);
    r.num("height", sh.height, ranges::kAltitude);
    r.num("radius", sh.radius, ranges::kLength);
    r.num("ridge_wavelength", sh.wavelength, ranges::kLength);
    r.num("angle", sh.angleDeg, ranges::kAngle);
    std::string file;
    r.text("file", file);
    if (!file.empty()) s.terrain.demFile = besideFile(r.file(), file);
    // a GeoTIFF knows its cell size: a base scene's (the Mont Blanc PNG's)
    // gives way to it unless this table sets cell_size too
    if (!file.empty() && isGeoTiffPath(file)) s.terrain.demCellSize = 0.0f;
    r.num("z_scale", s.terrain.demZScale, ranges::kDemZScale);
    r.num("z_offset", s.terrain.demZOffset, ranges::kAltitude);
    r.num("cell_size", s.terrain.demCellSize, ranges::kDemCellSize);
    r.flag("resample", s.terrain.demResample);
    r.num("ramp_start", s.terrain.rampStart, ranges::kAltitude);
    r.num("ramp_end", s.terrain.rampEnd, ranges::kAltitude);
}

void readHydraulic(TableReader& r, SceneSettings& s) {
    HydraulicSettings& h = s.hydraulicSettings;
    r.flag("enabled", s.hydraulic);
    r.num("gravity", h.gravity, ranges::kGravity);
    r.num("pipe_area", h.pipeArea, ranges::kPipeArea);
    r.num("rain_rate", h.rainRate, ranges::kRainRate);
    r.num("capacity", h.capacity, ranges::kCapacity);
    r.num("dissolve", h.dissolve, ranges::kRate);
    r.num("deposit", h.deposit, ranges::kRate);
    r.num("evaporation", h.evaporation, ranges::kRate);
    r.num("min_tilt", h.minTilt, ranges::kFraction);
    r.num("bedrock_hardness", h.bedrockHardness, ranges::kFraction);
    r.num("max_erosion_depth", h.maxErosionDepth, ranges::kDepth);
    r.flag("closed_boundary", h.closedBoundary);
}

void readThermal(TableReader& r, SceneSettings& s) {
    r.flag("enabled", s.thermal);
    r.num("talus_deg", s.thermalSettings.talusAngleDeg, ranges::kTalus);
    r.num("rate", s.thermalSettings.rate, ranges::kRate);
    r.flag("erode_bedrock", s.thermalSettings.erodeBedrock);
}

void readWaves(TableReader& r, SceneSettings& s) {
    WaveSettings& w = s.waveSettings;
    r.flag("enabled", s.waves);
    r.num("gravity", w.gravity, ranges::kGravity);
    r.num("courant", w.courant, ranges::kCourant);
    r.num("max_courant", w.maxCourant, ranges::kMaxCourant);
    r.num("dry_depth", w.dryDepth, ranges::kDryDepth);
    r.num("friction", w.friction, ranges::kManning);
    r.flag("advection", w.advection);
    r.child("swell", [&](TableReader& q) {
        w.swell.enabled = true;
        q.flag("enabled", w.swell.enabled);
        std::string edge;
        q.text("edge", edge);
        if (!edge.empty()) w.swell.edge = parseEdge(r.file(), edge);
        q.num("amplitude", w.swell.amplitude, ranges::kSwellAmplitude);
        q.num("period", w.swell.period, ranges::kSwellPeriod);
        w.swell.seaLevel = s.waterLevel;  // default: the scene's water level
        q.num("sea_level", w.swell.seaLevel, ranges::kAltitude);
        q.num("ramp_periods", w.swell.rampPeriods, ranges::kRampPeriods);
    });
    std::vector<WaveDrop> drops;
    const bool given = r.children("drops", [&](TableReader& q) {
        WaveDrop drop;
        q.num("time", drop.time, ranges::kDropTime);
        q.num("x", drop.x, ranges::kPosition);
        q.num("y", drop.y, ranges::kPosition);
        q.num("radius", drop.radius, ranges::kLength);
        q.num("height", drop.height, ranges::kAltitude);
        drops.push_back(drop);
    });
    if (given) w.drops = std::move(drops);
}

void readMaterial(TableReader& r, Material& m) {
    r.rgb("albedo", m.albedo);
    r.num("exponent", m.phongExponent);
}

// A rule's table switches it on unless it says `enabled = false`.
void readMaterials(TableReader& r, MaterialSet& m) {
    r.child("bedrock", [&](TableReader& q) { readMaterial(q, m.bedrock); });
    r.child("soil", [&](TableReader& q) {
        readMaterial(q, m.soil.material);
        q.num("cover_depth", m.soil.coverDepth);
    });
    r.child("vegetation", [&](TableReader& q) {
        VegetationRule& v = m.vegetation;
        v.enabled = true;
        q.flag("enabled", v.enabled);
        readMaterial(q, v.material);
        q.num("min_altitude", v.minAltitude);
        q.num("max_altitude", v.maxAltitude);
        q.num("altitude_fade", v.altitudeFade);
        q.num("max_slope", v.maxSlopeDeg);
    });
    r.child("snow", [&](TableReader& q) {
        SnowRule& v = m.snow;
        v.enabled = true;
        q.flag("enabled", v.enabled);
        readMaterial(q, v.material);
        q.num("line", v.line);
        q.num("altitude_fade", v.altitudeFade);
        q.num("max_slope", v.maxSlopeDeg);
    });
    r.child("wet", [&](TableReader& q) {
        q.num("darkening", m.wet.darkening);
        q.num("depth", m.wet.depth);
        q.num("exponent", m.wet.phongExponent);
    });
    r.child("water", [&](TableReader& q) {
        readMaterial(q, m.water.material);
        q.num("clarity", m.water.clarity);
    });
    r.child("foam", [&](TableReader& q) {
        m.foam.enabled = true;
        q.flag("enabled", m.foam.enabled);
        readMaterial(q, m.foam.material);
        q.num("max_depth", m.foam.maxDepth);
        q.num("min_gradient", m.foam.minDepthGradient);
    });
}

void readEnvironment(TableReader& r, EnvironmentSpec& e) {
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
        e.file = besideFile(r.file(), kind);
    }
    r.num("intensity", e.intensity, ranges::kRadiance);
    r.num("visibility", e.visibility, ranges::kVisibility);
    r.child("sky", [&](TableReader& q) {
        q.rgb("zenith", e.zenith, ranges::kRadiance);
        q.rgb("horizon", e.horizon, ranges::kRadiance);
        q.rgb("ground", e.ground, ranges::kRadiance);
    });
}

void readSun(TableReader& q, SunSpec& sun) {
    sun.enabled = true;
    q.flag("enabled", sun.enabled);
    q.num("latitude", sun.latitudeDeg, ranges::kLatitude);
    q.integer("day", sun.dayOfYear, ranges::kDayOfYear);
    q.num("hour", sun.hour, ranges::kHour);
    q.num("hours_per_frame", sun.hoursPerFrame, ranges::kHoursPerFrame);
    q.num("north", sun.northAzimuthDeg, ranges::kAngle);
    q.num("radius", sun.radiusDeg, ranges::kLightRadius);
    q.rgb("rgb", sun.rgb, ranges::kRadiance);
}

// [[lights.key]] tables replace the base scene's key lights.
void readLights(TableReader& r, LightSet& lights) {
    readEnvironment(r, lights.environment);
    std::vector<KeyLightSpec> keys;
    const bool given = r.children("key", [&](TableReader& q) {
        KeyLightSpec k;
        q.num("azimuth", k.azimuthDeg, ranges::kAngle);
        q.num("elevation", k.elevationDeg, ranges::kElevation);
        q.num("radius", k.radiusDeg, ranges::kLightRadius);
        q.rgb("rgb", k.rgb, ranges::kRadiance);
        keys.push_back(k);
    });
    if (given) lights.keys = std::move(keys);
    r.child("sun", [&](TableReader& q) { readSun(q, lights.sun); });
}

// [[camera.key]] tables replace the base scene's path.
void readCamera(TableReader& r, CameraPath& path) {
    r.num("fov", path.fovYDeg);
    std::vector<CameraKey> keys;
    const bool given = r.children("key", [&](TableReader& q) {
        CameraKey k;
        q.num("frame", k.frame);
        q.num("yaw", k.yawDeg);
        q.num("pitch", k.pitchDeg);
        q.num("distance", k.distance);
        q.numbers("target", k.target, 2, "[x, y] or [x, y, z], fractions of the extent (z: of the relief)");
        keys.push_back(k);
    });
    if (given) path.keys = std::move(keys);
}

// Plain values: the GI checks their ranges when it applies them (app/).
void readGi(TableReader& r, SceneSettings& s) {
    if (r.get("incremental")) {
        bool on = true;
        r.flag("incremental", on);
        s.gi.incremental = on;
    }
    if (r.get("tolerance")) {
        float tolerance = 0.0f;
        r.num("tolerance", tolerance);
        s.gi.tolerance = tolerance;
    }
    if (const toml::node* n = r.get("refresh")) {
        const std::optional<std::int64_t> every = integerOf(*n);
        if (!every) r.fail("refresh", "an integer");
        s.gi.refreshEvery = *every;
    }
}

// The file's table; a file that sets nothing is a mistake, not the default scene.
toml::table parseSceneFile(const std::string& file) {
    std::error_code ec;
    if (!std::filesystem::exists(file, ec)) throw IoError(file, "cannot open: no such file");
    if (!std::filesystem::is_regular_file(file, ec)) throw IoError(file, "is not a file");
    toml::table root;
    try {
        root = toml::parse_file(file);
    } catch (const toml::parse_error& e) {
        const auto& b = e.source().begin;
        throw IoError(file, "TOML syntax error at line " + std::to_string(b.line) + ", column " +
                                std::to_string(b.column) + ": " + boundedLine(e.description()));
    }
    if (root.empty()) throw IoError(file, "the scene file sets nothing (start with base = \"erosion\", say)");
    return root;
}

// `size = n` or `size = [nx, ny]`, each side checked before it is narrowed.
std::array<int, 2> readSize(TableReader& r) {
    std::array<int, 2> n{256, 256};
    const toml::node* sz = r.get("size");
    if (!sz) return n;
    if (integerOf(*sz)) {
        n[0] = n[1] = r.side("size", *sz);
    } else if (const toml::array* a = sz->as_array();
               a && a->size() == 2 && a->get(0)->is_integer() && a->get(1)->is_integer()) {
        n[0] = r.side("size", *a->get(0));
        n[1] = r.side("size", *a->get(1));
    } else {
        r.fail("size", "an integer or [nx, ny]");
    }
    return n;
}

// The keys at the top of the file, after `base` and `size`.
void readTopLevel(TableReader& r, SceneSettings& s) {
    r.text("name", s.name);
    r.num("cell_size", s.cellSize, ranges::kCellSize);
    std::int64_t seed = static_cast<std::int64_t>(s.seed);
    r.integer("seed", seed, ranges::kSeed);
    s.seed = static_cast<std::uint64_t>(seed);
    r.num("dt", s.dt, ranges::kDt);
    r.num("spin_up", s.spinUp, ranges::kSpinUp);
    r.integer("change_tile", s.changeTile, ranges::kChangeTile);
    r.num("soil_depth", s.soilDepth, ranges::kDepth);
    if (r.get("water_level")) {
        s.hasWaterLevel = true;
        r.num("water_level", s.waterLevel, ranges::kAltitude);
    }
}

}  // namespace

SceneSettings loadSceneFile(const std::string& file) {
    const toml::table root = parseSceneFile(file);
    TableReader r(root, file, "");
    std::string base;
    r.text("base", base);
    const auto [nx, ny] = readSize(r);
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
    readTopLevel(r, s);
    r.child("terrain", [&](TableReader& q) { readTerrain(q, s); });
    r.child("hydraulic", [&](TableReader& q) { readHydraulic(q, s); });
    r.child("thermal", [&](TableReader& q) { readThermal(q, s); });
    r.child("waves", [&](TableReader& q) { readWaves(q, s); });
    r.child("gi", [&](TableReader& q) { readGi(q, s); });
    if (r.child("materials", [&](TableReader& q) { readMaterials(q, s.materials); }))
        checkIn(file, [&] { validateMaterials(s.materials); });
    if (r.child("lights", [&](TableReader& q) { readLights(q, s.lights); }))
        checkIn(file, [&] { validateLights(s.lights); });
    if (r.child("camera", [&](TableReader& q) { readCamera(q, s.camera); }))
        checkIn(file, [&] { validateCameraPath(s.camera); });
    r.finish();
    if (s.terrain.kind == TerrainSource::Kind::Dem && s.terrain.demFile.empty())
        throw IoError(file, "'terrain.file' is missing: a \"dem\" terrain needs a heightmap (.png or .vdb)");
    checkIn(file, [&] { checkDimensions(s.nx, s.ny, s.cellSize); });
    return s;
}

}  // namespace terrain
