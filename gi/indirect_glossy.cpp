#include "gi/indirect_glossy.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "gi/glossy_exit_radiance.h"
#include "gi/indirect_scan_tables.h"

namespace terrain::gi {

namespace {

using namespace simd;

constexpr int kMaxBlocks = 64;              // receiver rows split into at most this many fixed blocks
constexpr int kGroup = kIndirectLaneGroup;  // receivers per kernel call (2 x 4 lanes)
constexpr int kNV = kGroup / 4;

inline bool anyLane(I4 m) { return (m[0] | m[1] | m[2] | m[3]) != 0; }

// A receiver row's scan inputs (loadReceiverRow), padded.
struct GlossyRow {
    const float *h0, *margin, *gx, *gy;
};

// Per group of receivers, per step with a new member: the segment moments
// (kNV x 4 vectors), the SH basis towards the receiver (kNV x 16) and the step.
struct GroupScratch {
    F4* moments;
    F4* basis;
    int* list;
};

// ---- algorithm: casting set, direction-dependent u, Eq. 12 ------------------
// Pass 1 (as gi/casting_set_scan): the height steps (Eq. 17); at each step
// with a new member in some lane, the clamped segment's moments Delta(s^p),
// p = 1..4, and the SH basis at the direction from the member back to the
// receiver, -d = -(cos phi c, sin phi c, s), s = t / sqrt(1 + t^2),
// c = 1 / sqrt(1 + t^2) for the member's slope t (0 in lanes without a new
// member). Returns the number of such steps.
int walkGroupGlossy(const ScanStep* hTab, const I4* steps, int nAny, int Y, int X0, const GlossyRow& row, float cosPhi,
                    float sinPhi, const GroupScratch& gs) {
    const float *h0 = row.h0, *margin = row.margin, *gx = row.gx, *gy = row.gy;
    F4* moments = gs.moments;
    F4* basis = gs.basis;
    int* list = gs.list;
    F4 M[kNV], g[kNV], q1[kNV];
    const F4 one = splat<F4>(1.0f), lim = splat<F4>(1e6f), nlim = splat<F4>(-1e6f), zero = splat<F4>(0.0f);
    const F4 cp = splat<F4>(-cosPhi), sp = splat<F4>(-sinPhi);
    for (int k = 0; k < kNV; ++k) {
        M[k] = splat<F4>(kNoBlocker);
        g[k] = load<F4>(gx + X0 + 4 * k) * splat<F4>(cosPhi) +
               load<F4>(gy + X0 + 4 * k) * splat<F4>(sinPhi);  // omega_min (Section 3)
        const F4 t = g[k] < nlim ? nlim : (g[k] > lim ? lim : g[k]);
        q1[k] = t / simd::sqrtv(one + t * t);
    }
    int n = 0;
    for (int i = 0; i < nAny; ++i) {
        const ScanStep& st = hTab[i];
        const std::ptrdiff_t o = Y * st.rowStep + X0;
        const float* a = st.field + (o + st.offA);
        const float* b = st.field + (o + st.offB);
        const F4 wa = load<F4>(st.w[0]), wb = load<F4>(st.w[1]), inv = load<F4>(st.w[2]);
        const I4 iv = {i, i, i, i};
        F4 t[kNV];
        I4 nw[kNV];
        I4 any = {0, 0, 0, 0};
        for (int k = 0; k < kNV; ++k) {
            t[k] = (((wa * load<F4>(a + 4 * k) + wb * load<F4>(b + 4 * k)) - load<F4>(h0 + X0 + 4 * k)) -
                    load<F4>(margin + X0 + 4 * k)) *
                   inv;
            nw[k] = (iv < steps[k]) & (t[k] > M[k]);  // Eq. 17
            any |= nw[k];
        }
        if (!anyLane(any)) continue;
        F4* mo = moments + static_cast<std::size_t>(n) * kNV * 4;
        F4* ba = basis + static_cast<std::size_t>(n) * kNV * kShCount;
        list[n++] = i;
        for (int k = 0; k < kNV; ++k) {
            M[k] = nw[k] ? t[k] : M[k];
            F4 tc = t[k] < g[k] ? g[k] : t[k];
            tc = tc < nlim ? nlim : (tc > lim ? lim : tc);
            const F4 sNew = tc / simd::sqrtv(one + tc * tc);
            const F4 sv = nw[k] ? sNew : q1[k];  // no new member: an empty segment
            const F4 p = q1[k], p2 = p * p, s2 = sv * sv;
            mo[4 * k + 0] = sv - p;
            mo[4 * k + 1] = s2 - p2;
            mo[4 * k + 2] = s2 * sv - p2 * p;
            mo[4 * k + 3] = s2 * s2 - p2 * p2;
            q1[k] = sv;
            // the member's own direction (its unclamped elevation), reversed
            F4 tm = t[k] < nlim ? nlim : (t[k] > lim ? lim : t[k]);
            tm = nw[k] ? tm : zero;
            const F4 ic = one / simd::sqrtv(one + tm * tm);
            F4 y[kShCount];
            shBasisLanes<F4>(cp * ic, sp * ic, -(tm * ic), y);
            for (int f = 0; f < kShCount; ++f) ba[kShCount * k + f] = nw[k] ? y[f] : zero;
        }
    }
    return n;
}

// Pass 2, per channel: u = Ebar . Y(-d) from the 16 planes' bilinear samples
// at the n steps of pass 1, accumulated with the moments; then Eq. 10's
// closed form in s. Out: nlp[(c * 4 + l) * pad + X].
void projectGroupGlossy(const ScanStep* rGeo, const float* const* rFields, int n, int Y, int X0, const GroupScratch& gs,
                        float* nlp, int pad, bool clamp) {
    const F4* moments = gs.moments;
    const F4* basis = gs.basis;
    const int* list = gs.list;
    const F4 zero = splat<F4>(0.0f);
    const F4 k0 = splat<F4>(0.70710678118654752440f), k1 = splat<F4>(0.61237243569579452455f);
    const F4 k2 = splat<F4>(0.79056941504209483300f), k3 = splat<F4>(0.23385358667337133659f);
    for (int c = 0; c < 3; ++c) {
        F4 A[kNV][4];
        for (int k = 0; k < kNV; ++k)
            for (int p = 0; p < 4; ++p) A[k][p] = zero;
        for (int e = 0; e < n; ++e) {
            const int i = list[e];
            const ScanStep& rs = rGeo[i];
            const std::ptrdiff_t ro = Y * rs.rowStep + X0, dB = rs.offB - rs.offA;
            const F4 rwa = load<F4>(rs.w[0]), rwb = load<F4>(rs.w[1]);
            const float* const* fp = rFields + static_cast<std::size_t>(i) * kGlossyFields + c * kShCount;
            const F4* mo = moments + static_cast<std::size_t>(e) * kNV * 4;
            const F4* ba = basis + static_cast<std::size_t>(e) * kNV * kShCount;
            F4 u[kNV];
            for (int k = 0; k < kNV; ++k) u[k] = zero;
            for (int f = 0; f < kShCount; ++f) {
                const float* pa = fp[f] + ro;
                for (int k = 0; k < kNV; ++k) {
                    // lanes without a new member have a zero basis; their samples are finite
                    const F4 v = rwa * load<F4>(pa + 4 * k) + rwb * load<F4>(pa + dB + 4 * k);
                    u[k] += v * ba[kShCount * k + f];
                }
            }
            if (clamp)  // GlossyPositivity::Clamp: a member sends no negative radiance
                for (int k = 0; k < kNV; ++k) u[k] = simd::vmax(u[k], zero);
            for (int k = 0; k < kNV; ++k)
                for (int p = 0; p < 4; ++p) A[k][p] += u[k] * mo[4 * k + p];
        }
        for (int k = 0; k < kNV; ++k) {
            float* base = nlp + static_cast<std::size_t>(c) * 4 * pad + X0 + 4 * k;
            simd::store(base, k0 * A[k][0]);
            simd::store(base + pad, k1 * A[k][1]);
            simd::store(base + 2 * pad, k2 * (A[k][2] - A[k][0]));
            simd::store(base + 3 * pad, k3 * (splat<F4>(5.0f) * A[k][3] - splat<F4>(6.0f) * A[k][1]));
        }
    }
}

// Scratch layout of one row block (floats; every part a multiple of 4).
struct BlockLayout {
    std::size_t gx, gy, h0, margin, nlp, moments, basis, total;
    BlockLayout(int pad, int nSteps) {
        const std::size_t p = static_cast<std::size_t>(pad), s = static_cast<std::size_t>(std::max(nSteps, 1));
        gx = 0;
        gy = gx + p;
        h0 = gy + p;
        margin = h0 + p;
        nlp = margin + p;
        moments = nlp + 12 * p;
        basis = moments + s * kNV * 4 * 4;
        total = basis + s * kNV * kShCount * 4 + 4;
    }
};

}  // namespace

VectorPyramidIndirect::VectorPyramidIndirect(const IndirectInputs& in, const IndirectSettings& settings,
                                             IndirectState& st)
    : in_(in),
      settings_(settings),
      st_(st),
      pad_(indirectRowPad(in.heights.nxr)),
      nSteps_(static_cast<int>(in.heights.steps.size())),
      nBlocks_(std::max(1, std::min(in.heights.nyr, kMaxBlocks))) {}

void VectorPyramidIndirect::beginFrame() {
    const HeightPyramid& pyr = in_.heights;
    const int nx = pyr.nx, ny = pyr.ny, nxr = pyr.nxr, nyr = pyr.nyr, m = in_.op.azimuths;
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr, plane = static_cast<std::size_t>(nx) * ny;
    if (!in_.directShade) throw InputError("glossy vector pyramid: the direct shading (incident SH) is required");
    const ShadeMaps& directShade = *in_.directShade;
    if (directShade.incident.size() != planeR * kGlossyFields || directShade.nx != nx || directShade.ny != ny)
        throw InputError("glossy vector pyramid: the direct shading is not a Phong shading of this field");
    for (int c = 0; c < 3; ++c) {
        VisibilityField& u = st_.u[static_cast<std::size_t>(c)];
        u.nxr = nxr;
        u.nyr = nyr;
        u.sh.resize(planeR * kShCount);
        st_.uZeroFrom = kShCount;  // every plane is written here
    }
    setUShadingLights(st_);
    GlossyIndirectState& gs = st_.glossy;
    const BlockLayout lay(pad_, nSteps_);
    gs.blockScratch.resize(static_cast<std::size_t>(nBlocks_) * lay.total);
    gs.blockList.resize(static_cast<std::size_t>(nBlocks_) * std::max(nSteps_, 1));
    gs.exitSh.resize(plane * kGlossyFields);
    const std::size_t tableSize = static_cast<std::size_t>(m) * nSteps_;
    st_.heightSteps.resize(tableSize);
    gs.steps.resize(tableSize);
    gs.fields.resize(tableSize * kGlossyFields);
    st_.stepsPerColumn.resize(static_cast<std::size_t>(m) * pad_);
    st_.stepsPerRow.resize(static_cast<std::size_t>(m) * nyr);
}

// E of bounce b - 1 at full resolution, and its pyramid (Section 5.3)
void VectorPyramidIndirect::buildPyramid(const BounceSource& previous) {
    const HeightPyramid& pyr = in_.heights;
    GlossyIndirectState& gs = st_.glossy;
    glossyExitRadiance(in_.gradX, in_.gradY, pyr.subsample, pyr.nxr, pyr.nyr, previous.shade->incident.data(),
                       previous.shade->rgb, in_.albedo, in_.shading, gs.rowScratch, gs.exitSh.data());
    buildScalarPyramids(gs.exitSh.data(), kGlossyFields, pyr, settings_.radiance, gs.pyramid);
}

void VectorPyramidIndirect::scan(int) {
    // ---- step table: heights, E geometry (identical for the 48 planes), valid prefixes
    GlossyIndirectState& gs = st_.glossy;
    const auto planeSteps = [&](int i, double c, double sn, std::size_t at, ValidPrefix& prefix) {
        const ScanStepInfo r = scanStepInfo(gs.pyramid.fields[0], i, c, sn);
        gs.steps[at] = r.step;
        const float** fp = gs.fields.data() + at * kGlossyFields;
        for (int f = 0; f < kGlossyFields; ++f) {
            // same layout in every plane's pyramid: only the base pointer differs
            const HeightPyramid& plane = gs.pyramid.fields[static_cast<std::size_t>(f)];
            const ScanStep rf = f == 0 ? r.step : scanStepInfo(plane, i, c, sn).step;
            fp[f] = rf.field + rf.offA;
        }
        prefix.narrow(r);
    };
    buildIndirectStepTable(in_.heights, in_.op.phi, pad_, st_.heightSteps, st_.stepsPerColumn, st_.stepsPerRow,
                           planeSteps);
    // ---- scan: casting sets, u = Ebar . Y(-d), Eq. 12, U through the folded wedge operator
    parallelFor(0, nBlocks_, 1, [&](int b0, int b1) {
        for (int block = b0; block < b1; ++block) scanBlock(block);
    });
}

void VectorPyramidIndirect::scanBlock(int block) {
    const int nyr = in_.heights.nyr;
    const BlockLayout lay(pad_, nSteps_);
    float* scr = st_.glossy.blockScratch.data() + static_cast<std::size_t>(block) * lay.total;
    int* list = st_.glossy.blockList.data() + static_cast<std::size_t>(block) * std::max(nSteps_, 1);
    const int yBegin = static_cast<int>(static_cast<long long>(nyr) * block / nBlocks_);
    const int yEnd = static_cast<int>(static_cast<long long>(nyr) * (block + 1) / nBlocks_);
    for (int Y = yBegin; Y < yEnd; ++Y) scanRow(Y, scr, list);
}

// Receiver row Y: its U rows zeroed, then every azimuth's casting sets into them.
void VectorPyramidIndirect::scanRow(int Y, float* scr, int* list) {
    const int nxr = in_.heights.nxr;
    const BlockLayout lay(pad_, nSteps_);
    loadReceiverRow(in_.heights, in_.gradX, in_.gradY, Y, pad_, scr + lay.gx, scr + lay.gy, scr + lay.h0,
                    scr + lay.margin);
    float* uRows[3][kShCount];
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < kShCount; ++i) {
            uRows[c][i] = st_.u[static_cast<std::size_t>(c)].plane(i) + static_cast<std::size_t>(Y) * nxr;
            std::fill(uRows[c][i], uRows[c][i] + nxr, 0.0f);
        }
    for (int j = 0; j < in_.op.azimuths; ++j) {
        castAzimuth(j, Y, scr, list);
        accumulateU(j, uRows, scr + lay.nlp);
    }
}

// Row Y's NLP coefficients along azimuth j, group by group (block scratch: nlp).
void VectorPyramidIndirect::castAzimuth(int j, int Y, float* scr, int* list) {
    const int nyr = in_.heights.nyr;
    const BlockLayout lay(pad_, nSteps_);
    const GlossyRow row{scr + lay.h0, scr + lay.margin, scr + lay.gx, scr + lay.gy};
    const GroupScratch gsc{reinterpret_cast<F4*>(scr + lay.moments), reinterpret_cast<F4*>(scr + lay.basis), list};
    const GlossyIndirectState& gs = st_.glossy;
    const std::size_t base = static_cast<std::size_t>(j) * nSteps_;
    const double phi = in_.op.phi[static_cast<std::size_t>(j)];
    const float cosPhi = static_cast<float>(std::cos(phi)), sinPhi = static_cast<float>(std::sin(phi));
    const int* colSteps = st_.stepsPerColumn.data() + static_cast<std::size_t>(j) * pad_;
    const int rowSteps = st_.stepsPerRow[static_cast<std::size_t>(j) * nyr + static_cast<std::size_t>(Y)];
    const I4 rowLimit = {rowSteps, rowSteps, rowSteps, rowSteps};
    for (int X0 = 0; X0 < pad_; X0 += kGroup) {
        I4 steps[kNV];
        int nAny = 0;
        for (int k = 0; k < kNV; ++k) {
            I4 cs;
            std::memcpy(&cs, colSteps + X0 + 4 * k, sizeof cs);
            steps[k] = cs < rowLimit ? cs : rowLimit;
            for (int l = 0; l < 4; ++l) nAny = std::max(nAny, steps[k][l]);
        }
        const int n = walkGroupGlossy(st_.heightSteps.data() + base, steps, nAny, Y, X0, row, cosPhi, sinPhi, gsc);
        projectGroupGlossy(gs.steps.data() + base, gs.fields.data() + base * kGlossyFields, n, Y, X0, gsc,
                           scr + lay.nlp, pad_, in_.shading.positivity == GlossyPositivity::Clamp);
    }
}

// U_c += G_j u_(c, j) over the sparse pattern (Eq. 21), all 16 rows
void VectorPyramidIndirect::accumulateU(int j, float* (*uRows)[kShCount], const float* nlp) const {
    const FoldedWedgeOperator& op = in_.op;
    const int P = op.patternSize(), nxr = in_.heights.nxr;
    const float* vals = op.values.data() + static_cast<std::size_t>(j) * P;
    for (int e = 0; e < P; ++e) {
        const int r = op.patternRow[static_cast<std::size_t>(e)];
        const float gval = vals[e];
        const int l = op.patternNlp[static_cast<std::size_t>(e)];
        for (int c = 0; c < 3; ++c) {
            float* __restrict dst = uRows[c][r];
            const float* __restrict w = nlp + static_cast<std::size_t>(c * 4 + l) * pad_;
            for (int X = 0; X < nxr; ++X) dst[X] += gval * w[X];
        }
    }
}

// L_b; its incident SH feeds bounce b + 1
void VectorPyramidIndirect::shade(int, ShadeMaps& out) {
    out.keepIncident = true;
    shadeTexels(in_.gradX, in_.gradY, in_.heights.subsample, in_.envVisibility, st_.lights.data(), 3, in_.albedo,
                in_.shading, out, false);
}

}  // namespace terrain::gi
