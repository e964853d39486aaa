#pragma once
// GLSL 3.30 core sources of the renderer (render/renderer.h describes the passes).
//
// Deferred shading: the mesh passes (kMeshVertex + kSurfacePointFragment)
// only record which surface point each pixel sees; the shading passes
// (kFullScreenVertex + kCommon + kTerrainFragment or kWaterFragment) then
// shade every pixel once, whatever the overdraw and the triangles' size.

namespace terrain::render::shaders {

// Shared by terrain, water and the shadow pass: the vertices of one chunk
// (render/terrain_lod.h) or of the full grid, uRow a row, every uStep-th grid
// point from uOrigin, clamped to the grid; positions fetched from the height
// texture (heights stream every frame).
inline constexpr const char* kMeshVertex = R"(#version 330 core
uniform sampler2D uHeight;   // RG32F: ground (m), water depth (m)
uniform ivec2 uGrid;         // nx, ny
uniform float uCell;         // m between grid points
uniform float uExag;         // vertical exaggeration
uniform mat4 uViewProj;
uniform int uWater;          // 1: the water surface (ground + depth)
uniform ivec2 uOrigin;       // the chunk's first grid point
uniform int uStep;           // grid points between its vertices
uniform int uRow;            // vertices per row
out vec3 vWorld;
out vec2 vCell;
out float vDepth;
void main() {
    ivec2 g = min(uOrigin + ivec2(gl_VertexID % uRow, gl_VertexID / uRow) * uStep, uGrid - 1);
    vec2 hw = texelFetch(uHeight, g, 0).rg;
    float z = hw.r;
    // Dry points of the water surface sit just under the ground, so the
    // surface ends at the shore and the depth test hides it on land.
    if (uWater == 1) z = hw.g > 0.01 ? hw.r + hw.g : hw.r - 0.2;
    vCell = vec2(g);
    vDepth = hw.g;
    vWorld = vec3(vec2(g) * uCell, z * uExag);
    gl_Position = uViewProj * vec4(vWorld, 1.0);
}
)";

inline constexpr const char* kShadowFragment = R"(#version 330 core
void main() {}
)";

// The mesh passes' fragment shader: the surface point this pixel sees, its
// grid coordinate and its height as the mesh has it (LOD may have coarsened
// it), alpha 1 (0, the clear value: no surface). Kept trivial on purpose: a
// software rasteriser pays a fragment shader per partly covered block of
// pixels, so small triangles and overdraw must find nothing to shade here.
inline constexpr const char* kSurfacePointFragment = R"(#version 330 core
uniform int uWater;
in vec3 vWorld;
in vec2 vCell;
in float vDepth;
out vec4 surfacePoint;
void main() {
    // A dry point of the water surface (render/water_triangles.h skips the
    // triangles where every fragment would end here).
    if (uWater == 1 && vDepth < 0.02) discard;
    surfacePoint = vec4(vCell, vWorld.z, 1.0);
}
)";

// Functions shared by the terrain and water shading passes.
inline constexpr const char* kCommon = R"(
const float PI = 3.14159265358979;
uniform sampler2D uSurface;   // RGBA32F: the mesh pass's surface points (kSurfacePointFragment)
uniform sampler2D uHeight;
uniform sampler2D uShade;     // RGBA32F: reflected sky and indirect light RGB (with the albedo), key visibility
uniform sampler2D uKey;       // RGBA32F: key shade RGB of a white surface, ambient
uniform sampler2D uAlbedo;    // RGBA32F: linear albedo RGB (the GI's albedo map), Phong exponent
uniform sampler2D uHydrology; // RGBA32F: discharge, velocity, net erosion, wetness (hydrology debug views only)
uniform vec2 uHydrologyMaxFlow, uHydrologyMaxGround;  // each map's largest magnitude
uniform sampler2D uReceiver;  // RG32F at the receiver grid: sky visibility, pyramid level
uniform sampler2D uEnv;       // RGB32F equirectangular environment (prefiltered: order-4 SH)
uniform sampler2DShadow uShadowMap;
uniform ivec2 uGrid;
uniform ivec2 uReceiverGrid;
uniform int uSubsample;
uniform float uCell;
uniform float uExag;
uniform vec3 uEye;
uniform vec3 uKeyDir;         // unit, towards the key light
uniform vec3 uKeyRgb;         // unshadowed key shade of a white surface facing the light
// Constants of the program variant (Renderer::shadingProgram), not uniforms,
// so that the compiler drops the branches a frame does not take: llvmpipe
// runs both sides of a branch on a block of pixels.
//   uLighting:   0 key only, 1 direct (sky + key), 2 global
//   uShadowMode: 0 soft visibility (engine), 1 shadow map, 2 none
//   uSpecular:   1 specular highlights and glints
//   uDebug:      a DebugView (0: none)
uniform vec2 uZRange;
uniform mat4 uLightViewProj;
uniform float uShadowTexel;
uniform float uHaze;          // extinction per metre of view distance (0: clear air)
out vec4 fragColor;

// The surface point under this pixel: its grid coordinate and world position
// (x, y from the grid coordinate, z as the mesh drew it). The stencil test
// runs a shading pass only on pixels where its surface was drawn.
void surfacePointHere(out vec2 cell, out vec3 world) {
    vec4 p = texelFetch(uSurface, ivec2(gl_FragCoord.xy), 0);
    cell = p.xy;
    world = vec3(p.xy * uCell, p.z);
}

vec2 uvOf(vec2 cell) { return (cell + 0.5) / vec2(uGrid); }
float surfaceAt(vec2 cell, bool water) {
    vec2 hw = texture(uHeight, uvOf(cell)).rg;
    return water ? hw.r + hw.g : hw.r;
}
// Full-resolution normal: central differences of the bilinear height field.
vec3 normalAt(vec2 cell, bool water) {
    float hl = surfaceAt(cell - vec2(1.0, 0.0), water), hr = surfaceAt(cell + vec2(1.0, 0.0), water);
    float hd = surfaceAt(cell - vec2(0.0, 1.0), water), hu = surfaceAt(cell + vec2(0.0, 1.0), water);
    float k = uExag / (2.0 * uCell);
    return normalize(vec3(-(hr - hl) * k, -(hu - hd) * k, 1.0));
}
vec2 receiverUv(vec2 cell) { return (cell / float(uSubsample) + 0.5) / vec2(uReceiverGrid); }

// Environment lookup: column = azimuth from +x towards +y, row 0 = zenith.
vec3 environment(vec3 d) {
    float u = atan(d.y, d.x) / (2.0 * PI);
    float v = 0.5 - asin(clamp(d.z, -1.0, 1.0)) / PI;
    return texture(uEnv, vec2(u, v)).rgb;
}

// Torrance-Sparrow (Heidrich & Seidel 1999, Eq. 1): f = F D G / (4 (n.l) (n.v)), returned
// as f * pi * (n.l), so that uKeyRgb * result is the reflected radiance (the
// key light's irradiance is pi * uKeyRgb * (n.l)).
float beckmann(float nh, float m) {
    float c2 = nh * nh;
    float t2 = (1.0 - c2) / max(c2, 1e-6);
    return exp(-t2 / (m * m)) / (PI * m * m * c2 * c2);
}
float smithG1(float c, float m) {  // Smith's term for a Beckmann surface (rational fit)
    if (c <= 0.0) return 0.0;
    float t = sqrt(max(1.0 - c * c, 0.0)) / c;
    if (t <= 0.0) return 1.0;
    float a = 1.0 / (m * t);
    return a < 1.6 ? (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a) : 1.0;
}
float schlick(float c, float f0) { return f0 + (1.0 - f0) * pow(1.0 - clamp(c, 0.0, 1.0), 5.0); }
float torranceSparrow(vec3 n, vec3 v, vec3 l, float m, float f0) {
    float nl = dot(n, l), nv = dot(n, v);
    if (nl <= 0.0 || nv <= 0.0) return 0.0;
    vec3 h = normalize(l + v);
    float nh = max(dot(n, h), 0.0), vh = max(dot(v, h), 0.0);
    return schlick(vh, f0) * beckmann(nh, m) * smithG1(nl, m) * smithG1(nv, m) * PI / (4.0 * nv);
}

// Classic shadow map (Williams 1978) with 3x3 percentage-closer filtering.
float shadowMapVisibility(vec3 world) {
    vec4 p = uLightViewProj * vec4(world, 1.0);
    vec3 q = p.xyz / p.w * 0.5 + 0.5;
    float s = 0.0;
    for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i) s += texture(uShadowMap, vec3(q.xy + vec2(i, j) * uShadowTexel, q.z - 0.0015));
    return s / 9.0;
}

// Key light: soft visibility, and the diffuse shade of a white surface.
void keyLight(vec2 uv, vec3 n, vec3 world, out float vis, out vec3 diffuse) {
    float nl = max(dot(n, uKeyDir), 0.0);
    if (uShadowMode == 0) {
        vis = texture(uShade, uv).a;
        diffuse = texture(uKey, uv).rgb;
    } else if (uShadowMode == 1) {
        vis = shadowMapVisibility(world);
        diffuse = uKeyRgb * nl * vis;
    } else {
        vis = 1.0;
        diffuse = uKeyRgb * nl;
    }
}
vec3 skyShade(vec2 uv) { return uLighting == 0 ? vec3(0.0) : texture(uShade, uv).rgb; }
// Aerial perspective: the surface's radiance fades along the view ray into
// the sky's radiance at the horizon in that direction (Beer-Lambert).
vec3 hazed(vec3 c, vec3 world) {
    if (uHaze <= 0.0) return c;
    vec3 ray = world - uEye;
    float t = exp(-uHaze * length(ray));
    vec2 h = length(ray.xy) > 0.0 ? normalize(ray.xy) : vec2(1.0, 0.0);
    return c * t + environment(vec3(h, 0.0)) * (1.0 - t);
}
// Beckmann roughness of a Phong exponent S: m = sqrt(2 / (S + 2)), the
// Phong-Beckmann correspondence S = 2 / m^2 - 2 of Walter et al. 2007.
float roughness(float exponent) { return sqrt(2.0 / (exponent + 2.0)); }
)";

inline constexpr const char* kTerrainFragment = R"(
void main() {
    vec2 cell;
    vec3 world;
    surfacePointHere(cell, world);
    vec2 uv = uvOf(cell);
    vec3 n = normalAt(cell, false);
    if (uDebug != 0) {
        vec3 c;
        vec3 r = texture(uReceiver, receiverUv(cell)).rgb;
        if (uDebug == 1) c = vec3(texture(uKey, uv).a);
        else if (uDebug == 2) c = vec3(r.r);
        else if (uDebug == 3) c = vec3(texture(uShade, uv).a);
        else if (uDebug == 4) c = n * 0.5 + 0.5;
        else if (uDebug == 5) c = vec3((r.g - uZRange.x) / max(uZRange.y - uZRange.x, 1e-3));
        else if (uDebug == 7) c = vec3(r.b * 2.0);
        else if (uDebug == 8) c = texture(uAlbedo, uv).rgb;
        else if (uDebug >= 9) {
            vec4 hy = texture(uHydrology, uv);
            vec4 maxima = max(vec4(uHydrologyMaxFlow, uHydrologyMaxGround), vec4(1e-30));
            if (uDebug == 9) c = vec3(0.3, 0.7, 1.0) * sqrt(hy.r / maxima.r);
            else if (uDebug == 10) c = vec3(hy.g / maxima.g);
            else if (uDebug == 11) {
                float t = clamp(hy.b / maxima.b, -1.0, 1.0);
                c = t > 0.0 ? vec3(1.0, 1.0 - t, 1.0 - t) : vec3(1.0 + t, 1.0 + t, 1.0);
            } else c = mix(vec3(0.9, 0.8, 0.6), vec3(0.0, 0.2, 0.8), hy.a);
        }
        else c = texture(uShade, uv).rgb + texture(uAlbedo, uv).rgb * texture(uKey, uv).rgb;
        fragColor = vec4(clamp(c, 0.0, 1.0), 1.0);
        return;
    }
    float vis;
    vec3 keyDiffuse;
    keyLight(uv, n, world, vis, keyDiffuse);
    // the GI bounced light off this albedo already: only the key light's share needs it
    vec4 material = texture(uAlbedo, uv);
    vec3 c = skyShade(uv) + material.rgb * keyDiffuse;
    if (uSpecular == 1)
        c += 0.35 * uKeyRgb * vis * torranceSparrow(n, normalize(uEye - world), uKeyDir, roughness(material.a), 0.04);
    fragColor = vec4(hazed(c, world), 1.0);
}
)";

inline constexpr const char* kWaterFragment = R"(
uniform sampler2D uSceneColor;     // the terrain shading pass's HDR colour
uniform sampler2D uTerrainPoints;  // the terrain mesh pass's surface points
uniform mat4 uViewProj;
uniform vec3 uViewAxis;            // unit: the camera's viewing direction
// Distance along the view axis to the terrain drawn at uv (none: far away).
float terrainDistance(vec2 uv) {
    vec4 p = texture(uTerrainPoints, uv);
    return p.a > 0.0 ? dot(vec3(p.xy * uCell, p.z) - uEye, uViewAxis) : 1e30;
}
// Screen-space reflection: march the reflected ray from p in growing steps,
// project each point and stop where it passes just behind the terrain drawn
// there; rgb is that terrain's colour, a its weight (0: no hit, fading out
// towards the screen's edges where the march loses sight of it). A clip
// position's w is its distance along the view axis.
vec4 terrainReflection(vec3 p, vec3 r) {
    float t = 0.004 * length(uEye - p);
    for (int i = 0; i < 16; ++i) {
        vec4 c = uViewProj * vec4(p + r * t, 1.0);
        if (c.w <= 0.0) break;
        vec3 ndc = c.xyz / c.w;
        if (abs(ndc.x) > 1.0 || abs(ndc.y) > 1.0 || ndc.z > 1.0) break;
        vec2 uv = ndc.xy * 0.5 + 0.5;
        float scene = terrainDistance(uv);
        float ray = c.w;
        if (ray > scene && ray - scene < 0.5 * t + 0.01 * ray) {
            vec2 edge = smoothstep(1.0, 0.85, abs(ndc.xy));
            return vec4(texture(uSceneColor, uv).rgb, edge.x * edge.y);
        }
        t *= 1.6;
    }
    return vec4(0.0);
}
void main() {
    vec2 cell;
    vec3 world;
    surfacePointHere(cell, world);
    vec2 uv = uvOf(cell);
    vec3 n = normalAt(cell, true);
    vec3 v = normalize(uEye - world);
    float vis;
    vec3 keyDiffuse;
    keyLight(uv, n, world, vis, keyDiffuse);
    // Mirror term: the terrain where the reflected ray meets it on screen,
    // else the prefiltered environment in that direction, dimmed by how much
    // of the sky the water sees.
    vec3 r = reflect(-v, n);
    float skyVis = clamp(texture(uReceiver, receiverUv(cell)).r, 0.0, 1.0);
    float f = schlick(max(dot(n, v), 0.0), 0.02);  // water, n = 1.33
    // The march is the water's dearest part: it runs only where Fresnel lets
    // the reflection show (grazing views), fading in over f = 0.05 .. 0.1.
    float reflective = smoothstep(0.05, 0.1, f);
    vec4 terrain = reflective > 0.0 ? terrainReflection(world, r) : vec4(0.0);
    vec3 mirror = mix(environment(r) * skyVis, terrain.rgb, terrain.a * reflective);
    vec4 material = texture(uAlbedo, uv);
    vec3 glint = uSpecular == 1 ? uKeyRgb * vis * torranceSparrow(n, v, uKeyDir, roughness(material.a), 0.02) : vec3(0.0);
    // Diffuse part: the water body and the bed seen through it, one albedo
    // in the GI's map (engine/material_maps.h), lit like the terrain.
    vec3 body = skyShade(uv) + material.rgb * keyDiffuse;
    vec3 c = f * mirror + glint + (1.0 - f) * body;
    fragColor = vec4(hazed(c, world), 1.0);  // opaque: the bed is in the body's albedo
}
)";

// Every full-screen pass: one triangle over the screen.
inline constexpr const char* kFullScreenVertex = R"(#version 330 core
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);  // one triangle over the screen
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

// The displayed colour of an HDR radiance: tone mapping (ACES fit) and sRGB
// encoding (uTonemap 0, the debug views: clamped, not tone mapped).
inline constexpr const char* kToneMap = R"(
uniform float uExposure;
uniform int uTonemap;
out vec4 fragColor;
vec3 aces(vec3 x) { return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0); }
vec3 srgb(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
vec4 displayed(vec3 c) {
    vec3 x = uTonemap == 1 ? aces(c * uExposure) : clamp(c, 0.0, 1.0);
    return vec4(srgb(x), 1.0);
}
)";

// A shading pass's pixels, displayed (under its surface's stencil test).
inline constexpr const char* kDisplayFragment = R"(
uniform sampler2D uHdr;  // the terrain's or the water's shading pass
void main() { fragColor = displayed(texelFetch(uHdr, ivec2(gl_FragCoord.xy), 0).rgb); }
)";

// The sky where no surface was drawn (render/sky.h): the sky model, the HDR
// image or the SH map, and a disc for each key light.
inline constexpr const char* kSkyFragment = R"(
const float PI = 3.14159265358979;
uniform sampler2D uEnv;       // the environment's SH, baked
uniform sampler2D uSkyImage;  // the HDR environment image (uSkyKind 2)
uniform int uSkyKind;         // 0 SH, 1 gradient, 2 image
uniform vec3 uZenith, uHorizon;
uniform float uImageScale;
uniform int uDiscs;
uniform vec3 uDiscDir[4];
uniform float uDiscCos[4];
uniform vec3 uDiscRadiance[4];
uniform mat4 uInvViewProj;
uniform vec3 uEye;
uniform vec2 uSize;
// Column = azimuth from +x towards +y, row 0 = zenith.
vec2 equirect(vec3 d) { return vec2(atan(d.y, d.x) / (2.0 * PI), 0.5 - asin(clamp(d.z, -1.0, 1.0)) / PI); }
vec3 background(vec3 d) {
    vec3 c;
    if (uSkyKind == 1) {
        c = uHorizon + (uZenith - uHorizon) * max(d.z, 0.0);  // below the horizon: the horizon's colour
    } else if (uSkyKind == 2) {
        c = uImageScale * texture(uSkyImage, equirect(d)).rgb;
    } else {
        c = texture(uEnv, equirect(normalize(vec3(d.xy, max(d.z, 0.0))))).rgb;
    }
    for (int k = 0; k < uDiscs; ++k) {
        float edge = 0.1 * (1.0 - uDiscCos[k]);  // a soft rim a tenth of the cap wide
        c += uDiscRadiance[k] * smoothstep(uDiscCos[k] - edge, uDiscCos[k] + edge, dot(d, uDiscDir[k]));
    }
    return c;
}
void main() {
    vec4 p = uInvViewProj * vec4(gl_FragCoord.xy / uSize * 2.0 - 1.0, 1.0, 1.0);
    fragColor = displayed(background(normalize(p.xyz / p.w - uEye)));
}
)";

}  // namespace terrain::render::shaders
