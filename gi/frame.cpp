#include "gi/frame.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/indirect.h"
#include "gi/indirect_bounces.h"
#include "gi/key_light_exact.h"
#include "gi/shading_tiles.h"

namespace terrain::gi {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// The folded wedge operator of the indirect scan: the environment's (when it
// gives V), or one of its own azimuths, cached.
const FoldedWedgeOperator& indirectScanOperator(const GiSettings& settings, GiState& st) {
    const int m = indirectScanAzimuths(settings);
    if (m == settings.visibility.azimuths && st.envOperator.shRows == kShCount) return st.envOperator;
    if (st.indirectOperatorAzimuths != m || st.indirectOperatorInterp != settings.visibility.interp) {
        st.indirectOperator = foldFullCircle(m, settings.visibility.interp);
        st.indirectOperatorAzimuths = m;
        st.indirectOperatorInterp = settings.visibility.interp;
    }
    return st.indirectOperator;
}

// What the indirect plan reads (gi/indirect_cache.h): this frame's direct
// light, height pyramid and geometry tiles, the state's radiance pyramid
// (the last pass's before buildDirectRadiancePyramid, this frame's after it).
IndirectPlanInputs indirectPlanInputs(const GiSettings& settings, const FrameChange& change,
                                      std::span<const double> phi, GiState& st) {
    return {.source = st.shade.rgb,
            .heights = st.pyramid,
            .pyramid = st.indirect.radiance,
            .geometryTiles = change.geometry ? &st.visibilityCache.geometryTiles : nullptr,
            .phi = phi,
            .tolerance = settings.tolerance,
            .blocker = &st.indirect.blocker,
            .sourceChanged = st.directChanged};
}

// Whether the indirect light is re-gathered by tiles this frame (`cached`:
// the frame keeps an indirect cache, incremental frames with a strategy that
// gathers by tiles); else every receiver, the cache dropped where it no
// longer describes the result.
bool startIndirect(const IndirectPlanInputs& planInputs, const FrameChange& change, bool cached, GiState& st) {
    if (!cached || (change.geometry && !change.heightsOnly)) {
        invalidateIndirectCache(st.indirectCache);
        return false;
    }
    return startIndirectPlan(planInputs, st.indirectCache);
}

// The texel tiles the indirect light's texel passes redo (gi/indirect_cache.h).
// The last pass's heights are the recorded ones when the pass before this one
// was on the geometry this frame replaced: this frame recomputed the
// geometry (a direct frame) and nothing else did since that pass (every
// frame that changes the heights recomputes the geometry and records them).
const ReceiverTiles* planTexels(ConstGridView heights, const FrameChange& change, const ReceiverTiles* only,
                                const AlbedoMap* albedo, GiState& st) {
    const IndirectCache& cache = st.indirectCache;
    const bool same = st.geometryVersion == cache.geometryVersion;
    const bool replacedLast =
        st.directUpdated && change.geometry && only != nullptr && st.geometryVersion == cache.geometryVersion + 1;
    const IndirectTexelInputs in{.gathered = only,
                                 .sameGeometry = same,
                                 .lastHeights = replacedLast ? &st.lastInputs.heights : nullptr,
                                 .heights = heights,
                                 .albedo = albedo,
                                 .pyramid = st.pyramid,
                                 .heightsDiffer = change.heightBox};
    return planIndirectTexels(in, st.indirectCache);
}

// The RGB radiance pyramid of this frame's direct light (bounce 0), which
// the indirect plan compares with the anchor's (gi/indirect_cache.h); the
// bounce then finds it built (IndirectInputs::radianceCurrent). Redone over
// the texels that read a changed one when it holds the last call's bounce 0.
void buildDirectRadiancePyramid(const GiSettings& settings, GiState& st) {
    IndirectState& ind = st.indirect;
    buildRadiancePyramid(st.shade.rgb, st.pyramid, settings.indirect.radiance, ind.radiance,
                         ind.radianceOfDirect ? st.directChanged : CellBox{});
    ind.radianceOfDirect = true;
}

// Indirect bounces over the last computed direct shade, re-gathered where
// its sources or the geometry within reach changed (incremental frames).
void runIndirectStage(ConstGridView heights, const GiSettings& settings, const FrameChange& change, GiState& st,
                      const AlbedoMap* albedo) {
    const auto t = Clock::now();
    const FoldedWedgeOperator& op = indirectScanOperator(settings, st);
    const bool cached = settings.incremental && gathersByTiles(settings.indirect, settings.shading);
    // the plan's inputs hold the state's pyramid: the last pass's when the
    // plan starts, this frame's once buildDirectRadiancePyramid has run
    const IndirectPlanInputs planInputs = indirectPlanInputs(settings, change, op.phi, st);
    const bool plans = startIndirect(planInputs, change, cached, st);
    const auto tPyramid = Clock::now();
    if (cached) buildDirectRadiancePyramid(settings, st);
    const double pyramidMs = msSince(tPyramid);
    const ReceiverTiles* only = plans ? planIndirectTiles(planInputs, st.indirectCache) : nullptr;
    const ReceiverTiles* texels = cached ? planTexels(heights, change, only, albedo, st) : nullptr;
    const IndirectInputs in{.heights = st.pyramid,
                            .gradX = st.gradX.cview(),
                            .gradY = st.gradY.cview(),
                            .op = op,
                            .envVisibility = st.envVisibility,
                            .direct = st.shade.rgb,
                            .directShade = &st.shade,
                            .albedo = albedo,
                            .shading = settings.shading,
                            .only = only,
                            .texels = texels,
                            .texelRuns = texels ? &st.indirectCache.texelRuns : nullptr,
                            .sameGeometry = !change.geometry,
                            .directChanged = settings.incremental ? st.directChanged : CellBox{},
                            .radianceCurrent = cached,
                            .memberLight = &st.shadedLight};
    computeIndirect(in, settings.indirect, st.indirect);
    noteOcclusionsRedone(cached ? texels : nullptr, cached ? in.texelRuns : nullptr, st.indirectCache);
    st.indirect.timings.pyramid += pyramidMs;  // bounce 0's pyramid, built before the plan
    st.indirect.timings.total += pyramidMs;
    st.directChanged = CellBox::none();  // the indirect light has read every change
    if (cached && only == nullptr)
        recordIndirectSource(st.shade.rgb, st.indirect.radiance, st.pyramid, static_cast<int>(op.phi.size()),
                             st.indirectCache);
    st.indirectCache.geometryVersion = st.geometryVersion;
    st.indirectRecomputed = only ? only->dirtyFraction() : 1.0;
    st.timings.indirect = msSince(t);
}

// The key light as the SH shading stage sees it (Section 6): its visibility
// is already restricted to the light's azimuthal extent and elevation
// interval, so V_key is the SH projection of "visible part of the light's
// region". Its incident radiance is that region's radiance times V_key: the
// product matrix is a scalar. The region's radiance gives the cap's
// irradiance at normal incidence, pi * RGB, over the region's solid angle.
ShadingLight keyShadingLight(const KeyLight& light, const VisibilityField& v) {
    ShadingLight out;
    const KeyLightExtent ext = keyLightExtent(light);
    const double solidAngle = (ext.phiEnd - ext.phiStart) * (static_cast<double>(ext.sinHigh) - ext.sinLow);
    out.visibility = &v;
    for (int ch = 0; ch < 3; ++ch) {
        ShMatrix& m = out.product[static_cast<std::size_t>(ch)];
        m.fill(0.0);
        const double radiance = solidAngle > 0.0 ? kPi * light.rgb[ch] / solidAngle : 0.0;
        for (int i = 0; i < kShCount; ++i) m[static_cast<std::size_t>(i * kShCount + i)] = radiance;
    }
    return out;
}

}  // namespace

void checkHeightsFinite(ConstGridView h, CellBox box) {
    box = box.cut(h.nx, h.ny);
    for (int y = box.y0; y < box.y1; ++y)
        for (int x = box.x0; x < box.x1; ++x)
            if (!std::isfinite(h(x, y)))
                throw InputError("heights: NaN or Inf at column " + std::to_string(x) + ", row " + std::to_string(y));
}

void computeGradient(ConstGridView h, float cellSize, Grid& gx, Grid& gy, RowSpan changed) {
    const int nx = h.nx, ny = h.ny;
    if (gx.nx != nx || gx.ny != ny || gy.nx != nx || gy.ny != ny) changed = {};
    gx.ensureSize(nx, ny);
    gy.ensureSize(nx, ny);
    const float inv2 = 0.5f / cellSize, inv1 = 1.0f / cellSize;
    const RowSpan rows = changed.grown(1).cut(ny);  // the central differences read one row either side
    // central differences inside, one-sided at the edges; the inside columns
    // and rows in plain loops the compiler vectorises
    parallelForRows(rows, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* h0 = h.row(y);
            float* dx = gx.data() + static_cast<std::size_t>(y) * nx;
            float* dy = gy.data() + static_cast<std::size_t>(y) * nx;
            if (nx > 1) {
                dx[0] = (h0[1] - h0[0]) * inv1;
                for (int x = 1; x < nx - 1; ++x) dx[x] = (h0[x + 1] - h0[x - 1]) * inv2;
                dx[nx - 1] = (h0[nx - 1] - h0[nx - 2]) * inv1;
            } else {
                dx[0] = 0.0f;
            }
            if (ny == 1) {
                std::fill(dy, dy + nx, 0.0f);
                continue;
            }
            const bool first = y == 0, last = y == ny - 1;
            const float* prev = h.row(first ? 0 : y - 1);
            const float* next = h.row(last ? ny - 1 : y + 1);
            const float scale = first || last ? inv1 : inv2;
            for (int x = 0; x < nx; ++x) dy[x] = (next[x] - prev[x]) * scale;
        }
    });
}

namespace {

// The stage's boundary: every input and setting checked before any work,
// but for the heights' values (runGiFrame checks those that are new).
void validateFrameInputs(ConstGridView heights, float cellSize, const GiLighting& lighting, const GiSettings& settings,
                         const AlbedoMap* albedo) {
    if (heights.nx < 1 || heights.ny < 1 || !heights.data) throw InputError("heights: empty grid");
    if (!std::isfinite(cellSize) || cellSize <= 0.0f) throw InputError("cell size must be positive and finite");
    validateGiSettings(settings);
    for (const KeyLight& k : lighting.keys) validateKeyLight(k);
    if (const auto& g = lighting.gradient)
        for (const std::array<float, 3>* colour : {&g->zenith, &g->horizon, &g->ground})
            for (float v : *colour)
                if (!std::isfinite(v) || v < 0.0f)
                    throw InputError("sky gradient: every colour must be finite and >= 0");
    for (const ShVector& c : lighting.environment.c)
        for (double v : c)
            if (!std::isfinite(v)) throw InputError("environment light: NaN or Inf coefficient");
    if (!albedo) return;
    for (const Grid& g : albedo->channel)
        if (!g.empty() && (g.nx != heights.nx || g.ny != heights.ny))
            throw InputError("albedo map size differs from the heights");
    for (const Grid& g : albedo->phongLobe)
        if (!g.empty() && (g.nx != heights.nx || g.ny != heights.ny))
            throw InputError("Phong exponent map size differs from the heights");
}

// Shading amortisation (Nowrouzezahrai & Snyder 2009, Section 7): on static
// geometry (or, with incremental frames, geometry that moved by less than the
// tolerance everywhere), frames with the same key alternate between updating
// the direct and the indirect light. Sets st.directUpdated / st.indirectUpdated.
void planAmortisation(ConstGridView heights, const GiSettings& settings, GiState& st) {
    const std::array<int, 7> key = {heights.nx,
                                    heights.ny,
                                    settings.subsample,
                                    settings.indirect.bounces,
                                    settings.visibility.azimuths,
                                    static_cast<int>(settings.shading.brdf),
                                    settings.indirect.azimuths};
    const bool amortised = settings.indirect.amortise && settings.indirect.bounces > 0 && !st.geometryChanged &&
                           st.amortiseReady && st.amortiseKey == key;
    st.directUpdated = !amortised || st.amortisePhase == 0;
    st.indirectUpdated = settings.indirect.bounces > 0 && (!amortised || st.amortisePhase == 1);
    st.amortisePhase = amortised ? 1 - st.amortisePhase : 0;
    st.amortiseReady = true;
    st.amortiseKey = key;
}

// The environment's visibility V at the receivers; with sub-sampling and
// footprint tangent planes, omega_min from each receiver's footprint box.
// gradientRows: the rows of the gradients that changed since the last call.
void environmentVisibility(const GiSettings& settings, int shRows, const ReceiverTiles* only, RowSpan gradientRows,
                           GiState& st) {
    if (st.envOperatorAzimuths != settings.visibility.azimuths || st.envOperatorInterp != settings.visibility.interp ||
        st.envOperator.shRows != shRows) {
        st.envOperator = foldFullCircle(settings.visibility.azimuths, settings.visibility.interp);
        if (shRows == 1) st.envOperator = firstRowOnly(std::move(st.envOperator));
        if (shRows == 0) st.envOperator = horizonsOnly(std::move(st.envOperator));
        st.envOperatorAzimuths = settings.visibility.azimuths;
        st.envOperatorInterp = settings.visibility.interp;
        const std::vector<double>& phi = st.envOperator.phi;
        st.envCosSin.resize(2 * phi.size());
        for (std::size_t j = 0; j < phi.size(); ++j) {
            st.envCosSin[2 * j] = static_cast<float>(std::cos(phi[j]));
            st.envCosSin[2 * j + 1] = static_cast<float>(std::sin(phi[j]));
        }
    }
    const bool footprint = settings.subsample > 1 && settings.visibility.footprintTangent;
    if (footprint)
        computeFootprintBox(st.gradX.cview(), st.gradY.cview(), settings.subsample, st.footprint, gradientRows);
    VisibilityTarget envTarget;
    envTarget.op = &st.envOperator;
    envTarget.footprint = footprint ? &st.footprint : nullptr;
    computeVisibility(st.pyramid, st.gradX.cview(), st.gradY.cview(), settings.visibility, envTarget,
                      st.visibilityState, st.envVisibility, only);
}

// Each key light's own visibility over its azimuthal extent and elevation
// interval (Section 6); operators cached per light.
// With `only`, a key light whose region of the sky is the same as last frame
// recomputes only those tiles (the heights changed, or `brighter`: on the
// same heights the lights are brighter than the tiles' drift allows); a new
// region, all.
void keyLightVisibility(const GiLighting& lighting, const GiSettings& settings, const FrameChange& change,
                        const ReceiverTiles* only, bool brighter, GiState& st) {
    const std::size_t nKeys = lighting.keys.size();
    st.keyOperators.resize(nKeys);
    st.keyOperatorLights.resize(nKeys);
    st.keyVisibility.resize(nKeys);
    const bool footprint = settings.subsample > 1 && settings.visibility.footprintTangent;
    for (std::size_t k = 0; k < nKeys; ++k) {
        if (!change.keyVisibility(k) && !brighter) continue;
        ++st.keyVisibilitiesRecomputed;
        const KeyLight& light = lighting.keys[k];
        const KeyLightExtent ext = keyLightExtent(light);
        // with the exact cosine the shading reads the visible fraction alone (V_00)
        const int shRows = settings.keyLightExactCosine ? 1 : kShCount;
        if (st.keyOperators[k].azimuths != settings.keyLightAzimuths || st.keyOperators[k].shRows != shRows ||
            !sameSkyRegion(st.keyOperatorLights[k], light)) {
            st.keyOperators[k] = foldPartialRange(ext.phiStart, ext.phiEnd, settings.keyLightAzimuths);
            if (shRows == 1) st.keyOperators[k] = firstRowOnly(std::move(st.keyOperators[k]));
            st.keyOperatorLights[k] = light;
        }
        VisibilityTarget target;
        target.op = &st.keyOperators[k];
        target.window = true;
        target.sinLow = ext.sinLow;
        target.sinHigh = ext.sinHigh;
        target.footprint = footprint ? &st.footprint : nullptr;
        VisibilitySettings ks = settings.visibility;
        ks.azimuths = settings.keyLightAzimuths;
        computeVisibility(st.pyramid, st.gradX.cview(), st.gradY.cview(), ks, target, st.visibilityState,
                          st.keyVisibility[k], change.keyRegion[k] ? nullptr : only);
    }
}

// The environment as the direct shading lights it. With the exact ambient a
// Lambert shade takes the sky's constant part (its band-0 SH coefficient)
// from the ambient map (addConstantSky), or, when the ambient's parts are
// there, the analytic sky's whole function (addGradientSky); only the rest
// goes through the SH product.
struct EnvironmentSplit {
    bool splitSky = false;                   // the constant part is lit from the ambient map
    bool exactSky = false;                   // the analytic sky is lit from the ambient's parts
    ShRgb sh;                                // what goes through the SH product
    float constant[3] = {0.0f, 0.0f, 0.0f};  // RGB radiance lit from the ambient map (splitSky)
};

EnvironmentSplit splitEnvironment(const GiLighting& lighting, const GiSettings& settings, bool skyParts) {
    EnvironmentSplit e;
    e.splitSky = settings.ambient == AmbientMethod::Horizons && settings.shading.brdf == Brdf::Lambert;
    e.exactSky = e.splitSky && lighting.gradient && skyParts;
    if (e.exactSky) return e;
    e.sh = lighting.environment;
    if (!e.splitSky) return e;
    for (std::size_t ch = 0; ch < 3; ++ch) {
        e.constant[ch] = static_cast<float>(e.sh.c[ch][0] * kShY00);
        e.sh.c[ch][0] = 0.0;
    }
    return e;
}

ShadingLight environmentShadingLight(const ShRgb& radiance, const VisibilityField& v) {
    ShadingLight out;
    out.visibility = &v;
    for (std::size_t ch = 0; ch < 3; ++ch) out.product[ch] = shProductMatrix(radiance.c[ch]);
    return out;
}

// Whether the frame reads the environment's SH visibility V: the paper's SH
// ambient does, and so does an environment with a part that goes through the
// SH product. The exact ambient and sky read the horizons alone, so a
// uniform or analytic sky (the sun and key lights have their own
// visibility) needs no V. The sky's parts come with the ambient whenever
// there is a sky gradient (runDirectStages).
bool readsEnvironmentSh(const GiLighting& lighting, const GiSettings& settings) {
    if (settings.ambient == AmbientMethod::ShProduct) return true;
    const EnvironmentSplit e = splitEnvironment(lighting, settings, lighting.gradient.has_value());
    VisibilityField none;
    return lightContributes(environmentShadingLight(e.sh, none));
}

// The ambient map from the environment scan's horizons (gi/ambient_horizon.h),
// over the environment's azimuths (the scan's own table holds the last key
// light's by now). It depends on the geometry alone: the frames recompute it
// where the environment's V was recomputed, not when only the lights change.
void exactAmbient(ConstGridView heights, float cellSize, const GiSettings& settings, bool withSkyParts, GiState& st,
                  const TexelRuns* runs) {
    const bool footprint = settings.subsample > 1 && settings.visibility.footprintTangent;
    const AmbientInputs in{.gradX = st.gradX.cview(),
                           .gradY = st.gradY.cview(),
                           .heights = heights,
                           .cellSize = cellSize,
                           .subsample = settings.subsample,
                           .env = &st.envVisibility,
                           .cosSin = st.envCosSin,
                           .footprint = footprint ? &st.footprint : nullptr};
    ShadeMaps& sh = st.shade;
    const AmbientOutputs out{sh.ambient, withSkyParts ? &sh.skyBelow : nullptr, withSkyParts ? &sh.skyRising : nullptr};
    ambientFromHorizons(in, out, st.ambientScratch, runs);
    sh.skyParts = withSkyParts;
}

// Direct light at every texel: the lighting's SH product matrices once per
// frame, then the shading (Section 7); key lights through the SH clamped
// cosine, or with the exact cosine (GiSettings::keyLightExactCosine). With
// `runs` only those texels, the others keep the last frame's light.
void directShading(const GiLighting& lighting, const GiSettings& settings, const AlbedoMap* albedo, GiState& st,
                   const TexelRuns* runs) {
    const std::size_t nKeys = lighting.keys.size();
    const bool exactKeys = settings.keyLightExactCosine;
    st.shade.keepIncident = readsIncidentSh(settings.indirect, settings.shading);
    const bool shAmbient = settings.ambient == AmbientMethod::ShProduct;
    const EnvironmentSplit sky = splitEnvironment(lighting, settings, st.shade.skyParts);
    st.shadingLights.resize(1 + (exactKeys ? 0 : nKeys));
    // the shading leaves the environment out when nothing of it goes through SH
    st.shadingLights[0] = environmentShadingLight(sky.sh, st.envVisibility);
    st.shadedLight = sky.sh;
    for (std::size_t k = 0; k < (exactKeys ? 0 : nKeys); ++k) {
        st.shadingLights[k + 1] = keyShadingLight(lighting.keys[k], st.keyVisibility[k]);
        const ShRgb cap = keyLightSh(lighting.keys[k]);
        for (std::size_t ch = 0; ch < 3; ++ch)
            for (std::size_t i = 0; i < static_cast<std::size_t>(kShCount); ++i)
                st.shadedLight.c[ch][i] += cap.c[ch][i];
    }
    // The indirect light re-reads the texels whose light changed, which can
    // be far fewer than those redone (a key light's tile recomputed to the
    // same visible fractions): its pyramids and bounds cost by their box.
    // The runs' texels are copied before and compared after, which costs
    // their count, not their bounding box (changes at several places).
    if (runs)
        for (int c = 0; c < 3; ++c) copyRuns(st.shade.rgb[c].cview(), *runs, st.shadeBefore[c]);
    shadeTexels(st.gradX.cview(), st.gradY.cview(), settings.subsample, st.envVisibility, st.shadingLights.data(),
                static_cast<int>(st.shadingLights.size()), albedo, settings.shading, st.shade, shAmbient, runs);
    if (sky.exactSky)
        addGradientSky({st.shade.ambient, &st.shade.skyBelow, &st.shade.skyRising}, *lighting.gradient, albedo,
                       st.shade.rgb, runs);
    else if (sky.splitSky)
        addConstantSky(st.shade.ambient, sky.constant, albedo, st.shade.rgb, runs);
    if (exactKeys)
        for (std::size_t k = 0; k < nKeys; ++k)
            addKeyLightExactCosine(lighting.keys[k], st.keyVisibility[k], settings.subsample, st.gradX.cview(),
                                   st.gradY.cview(), albedo, st.shade.rgb, runs);
    if (!runs) {
        st.directChanged = CellBox{};  // every texel
        return;
    }
    for (int c = 0; c < 3; ++c)
        st.directChanged = st.directChanged.joined(differingInRuns(st.shadeBefore[c], st.shade.rgb[c].cview(), *runs));
}

// Which receivers' visibility the frame recomputes, planned before any stage
// runs so that amortisation sees whether the geometry moved beyond the
// tolerance: when only the heights changed, the tiles whose cached V may have
// drifted beyond it (gi/visibility_cache.h; the last frame's pyramid has the
// same steps); otherwise every receiver.
struct GeometryPlan {
    bool tiled = false;            // recompute the visibility cache's dirty tiles only
    bool withinTolerance = false;  // tiled, and no tile's V drifted beyond the tolerance
};

// What each key light's cached visibility answers for.
std::vector<KeyLightRegion> keyLightRegions(const GiLighting& lighting, const GiSettings& settings) {
    std::vector<KeyLightRegion> out;
    for (const KeyLight& k : lighting.keys) {
        const KeyLightExtent e = keyLightExtent(k);
        out.push_back({e.phiStart, e.phiEnd, e.sinLow, e.sinHigh, std::max({k.rgb[0], k.rgb[1], k.rgb[2]}),
                       settings.keyLightExactCosine});
    }
    return out;
}

GeometryPlan planGeometry(ConstGridView heights, const GiLighting& lighting, const GiSettings& settings,
                          const FrameChange& change, GiState& st) {
    GeometryPlan plan;
    if (!change.geometry) return plan;
    const auto t = Clock::now();
    plan.tiled = change.heightsOnly && !st.lastInputs.heights.empty() && shouldPlanTiles(st.visibilityCache);
    if (plan.tiled) {
        VisibilityCache& cache = st.visibilityCache;
        // none without a bounce
        const int indirectAzimuths = settings.indirect.bounces == 0 ? 0 : indirectScanAzimuths(settings);
        planVisibilityTiles(st.lastInputs.heights.cview(), heights, st.pyramid, settings.visibility,
                            keyLightRegions(lighting, settings), settings.tolerance, cache, change.heightBox,
                            indirectAzimuths);
        plan.withinTolerance =
            cache.tiles.dirtyCount() == 0 && cache.keyTiles.dirtyCount() == 0 && cache.geometryTiles.dirtyCount() == 0;
    }
    st.timings.visibility = msSince(t);
    return plan;
}

// The texels whose direct light, and those whose exact ambient, can differ
// from the last frame's (gi/shading_tiles.h), or null for every texel: only
// when the heights alone changed, the visibility was recomputed by tiles and
// the last direct shading is of the recorded inputs.
struct DirectRuns {
    const TexelRuns* shading = nullptr;
    const TexelRuns* ambient = nullptr;
};

DirectRuns directRuns(ConstGridView heights, const FrameChange& change, const GeometryPlan& plan, GiState& st) {
    const bool keyRegions = std::find(change.keyRegion.begin(), change.keyRegion.end(), true) != change.keyRegion.end();
    if (!plan.tiled || change.radiance || keyRegions || st.directStale || !st.lastInputs.valid ||
        st.shade.nx != heights.nx || st.shade.ny != heights.ny || st.lastInputs.heights.nx != heights.nx ||
        st.lastInputs.heights.ny != heights.ny)
        return {};
    const VisibilityCache& cache = st.visibilityCache;
    changedDirectTexels(st.lastInputs.heights.cview(), heights, cache.tiles, st.keyReceiversChanged,
                        st.pyramid.subsample, st.texelRects, st.ambientRuns, st.shadingRuns, change.heightBox);
    return {&st.shadingRuns, &st.ambientRuns};
}

// The direct light's stages: geometry (gradient, pyramid, environment V)
// where it changed, each key light's V where its region of the sky or the
// geometry changed, and the shading; the visibility over the plan's tiles.
void runDirectStages(ConstGridView heights, float cellSize, const GiLighting& lighting, const GiSettings& settings,
                     const FrameChange& change, const GeometryPlan& plan, const AlbedoMap* albedo, GiState& st) {
    auto t = Clock::now();
    const ReceiverTiles* only = nullptr;     // the environment's tiles to recompute (null: all)
    const ReceiverTiles* keyOnly = nullptr;  // the key lights'
    const int shRows = readsEnvironmentSh(lighting, settings) ? kShCount : settings.minEnvironmentShRows;
    // Tiles keep the last V: only when it has the planes this frame reads.
    const bool samePlanes = st.envVisibility.planes == shRows;
    // V newly read on unchanged geometry (the lighting now has a part that
    // goes through SH): the environment's scan reruns for every receiver.
    const bool shMissing = !change.geometry && st.envVisibility.planes < shRows;
    RowSpan gradientRows;  // the gradients' rows this frame changes (every row unless told otherwise)
    if (change.geometry) {
        ++st.geometryVersion;
        // when the buffers hold the recorded heights' results, the passes
        // that go row by row redo the changed rows alone, and the height
        // pyramid what the box of changed cells reaches
        const CellBox box = change.heightsOnly && st.geometryOfRecord ? change.heightBox : CellBox{};
        const RowSpan rows = box.rows();
        st.geometryOfRecord = false;  // until this frame's inputs are recorded
        computeGradient(heights, cellSize, st.gradX, st.gradY, rows);
        gradientRows = rows.grown(1);
        st.timings.gradient = msSince(t);
        t = Clock::now();
        buildHeightPyramid(heights, cellSize, settings.subsample, settings.pyramid, st.pyramid, box);
        st.timings.pyramid = msSince(t);
        t = Clock::now();
    }
    if (change.geometry || shMissing) {
        const bool tiled = plan.tiled && samePlanes;
        if (change.geometry && !plan.tiled)
            resetVisibilityCache(st.pyramid, heights, st.visibilityCache);
        else if (!tiled)
            forgetEnvironmentDrift(st.visibilityCache);
        only = tiled ? &st.visibilityCache.tiles : nullptr;
        keyOnly = plan.tiled ? &st.visibilityCache.keyTiles : nullptr;
        environmentVisibility(settings, shRows, only, gradientRows, st);
        st.timings.visibility += msSince(t);
        st.receiversRecomputed = tiled ? st.visibilityCache.tiles.dirtyFraction() : 1.0;
    }
    t = Clock::now();
    // the same heights under brighter key lights: the key tiles whose drift now counts beyond the tolerance
    const bool brighter =
        !change.geometry && change.radiance && !lighting.keys.empty() &&
        planKeyBrightness(keyLightRegions(lighting, settings), settings.tolerance, st.visibilityCache);
    if (brighter) keyOnly = &st.visibilityCache.keyTiles;
    if (keyOnly) keepKeyVisibility(st.keyVisibility, *keyOnly, st.keyBefore);
    keyLightVisibility(lighting, settings, change, keyOnly, brighter, st);
    if (keyOnly) keyReceiversChanged(st.keyVisibility, *keyOnly, st.keyBefore, st.keyReceiversChanged);
    st.timings.keyVisibility = msSince(t);
    t = Clock::now();
    const DirectRuns runs = directRuns(heights, change, plan, st);
    if (settings.ambient == AmbientMethod::Horizons) {
        // the sky's parts ride with the ambient; a sky gradient new to this
        // geometry needs them over the whole field
        const bool withSkyParts = lighting.gradient.has_value();
        const bool partsMissing = withSkyParts && !st.shade.skyParts;
        if (change.geometry || partsMissing || shMissing)
            exactAmbient(heights, cellSize, settings, withSkyParts, st,
                         partsMissing || shMissing ? nullptr : runs.ambient);
    }
    directShading(lighting, settings, albedo, st, runs.shading);
    st.timings.shading = msSince(t);
}

}  // namespace

void runGiFrame(ConstGridView heights, float cellSize, const GiLighting& lighting, const GiSettings& settings,
                GiState& st, const AlbedoMap* albedo) {
    const auto t0 = Clock::now();  // the whole frame: input checks and the comparison included
    validateFrameInputs(heights, cellSize, lighting, settings, albedo);
    const bool refresh =
        settings.incremental && settings.refreshEvery > 0 && st.framesSinceRefresh + 1 >= settings.refreshEvery;
    const FrameChange change = settings.incremental && !refresh
                                   ? compareFrameInputs(st.lastInputs, heights, cellSize, lighting, settings, albedo)
                                   : everythingChanged(lighting.keys.size());
    // heights equal to the recorded ones bit for bit were checked when recorded
    checkHeightsFinite(heights, change.newHeights);
    st.framesSinceRefresh = refresh || !settings.incremental ? 0 : st.framesSinceRefresh + 1;
    st.timings = GiTimings{};
    st.receiversRecomputed = 0.0;
    st.indirectRecomputed = 0.0;
    st.keyVisibilitiesRecomputed = 0;
    if (!change.any() && !st.directStale && !st.indirectStale) {
        st.directUpdated = st.indirectUpdated = false;  // the cached results are this frame's
        // the terrain stopped changing everywhere: the next change is planned (gi/plan_skips.h)
        st.visibilityCache.skips = {};
        st.indirectCache.skips = {};
        st.timings.total = msSince(t0);
        return;
    }
    const GeometryPlan plan = planGeometry(heights, lighting, settings, change, st);
    if (settings.incremental) st.geometryChanged = change.geometry && !plan.withinTolerance;
    planAmortisation(heights, settings, st);
    if (!st.directUpdated) {
        // indirect only: geometry, pyramid, visibility and direct shade are the
        // last direct frame's, and so are the recorded inputs (below)
        runIndirectStage(heights, settings, change, st, albedo);
        st.directStale = change.any();
        st.indirectStale = false;
    } else {
        runDirectStages(heights, cellSize, lighting, settings, change, plan, albedo, st);
        st.directStale = false;
        if (st.indirectUpdated) {
            runIndirectStage(heights, settings, change, st, albedo);
            st.indirectStale = false;
        } else if (settings.indirect.bounces > 0) {
            sumDirectAndIndirect(st.shade.rgb, st.indirect);  // the last indirect light on the new direct shade
            st.indirectStale = true;
        }
    }
    // An indirect-only frame leaves the record at the last direct frame's
    // inputs: the next direct frame then sees every change it skipped.
    if (!settings.incremental) {
        st.lastInputs.valid = false;
    } else if (st.directUpdated) {
        recordFrameInputs(heights, cellSize, lighting, settings, albedo, change, st.lastInputs);
        if (change.geometry) st.geometryOfRecord = true;
    }
    st.timings.total = msSince(t0);
}

void shadeDirect(const GiLighting& lighting, const GiSettings& settings, const AlbedoMap* albedo, GiState& st) {
    directShading(lighting, settings, albedo, st, nullptr);
}

void shadeKeyLight(const GiState& st, const GiSettings& settings, const GiLighting& lighting, int k, ShadeMaps& scratch,
                   std::array<Grid, 3>& out) {
    if (k < 0 || k >= static_cast<int>(lighting.keys.size()) || k >= static_cast<int>(st.keyVisibility.size()))
        throw InputError("shadeKeyLight: no key light " + std::to_string(k) + " in the last frame");
    const KeyLight& light = lighting.keys[static_cast<std::size_t>(k)];
    const VisibilityField& v = st.keyVisibility[static_cast<std::size_t>(k)];
    if (settings.keyLightExactCosine) {
        for (Grid& g : out) g.resize(st.gradX.nx, st.gradX.ny, 0.0f);
        addKeyLightExactCosine(light, v, settings.subsample, st.gradX.cview(), st.gradY.cview(), nullptr, out);
        return;
    }
    const ShadingLight sl = keyShadingLight(light, v);
    shadeTexels(st.gradX.cview(), st.gradY.cview(), settings.subsample, st.envVisibility, &sl, 1, nullptr,
                settings.shading, scratch, false);
    out = scratch.rgb;
}

}  // namespace terrain::gi
