#ifndef SHADOWLAB_RASTER_RESOLVE_ABI_H
#define SHADOWLAB_RASTER_RESOLVE_ABI_H
// The interface between the rasterizer (C++) and its shaders (GLSL), written once and read by
// both: resolve.frag's parameter block, the descriptor bindings of the one descriptor set, the
// specialization constant ids and the codes the shader switches on (kinds.h's filters and light
// types). glslang reads it through GL_GOOGLE_include_directive (raster/CMakeLists.txt passes the
// include directories), C++ as shadowlab/raster/resolve_abi.h. The C++ side checks the block's std140 layout with
// static_asserts below.
#include "shadowlab/scenes/kinds.h"

#ifdef __cplusplus
#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

namespace shadowlab::raster::abi {
using mat4 = glm::mat4;
using vec4 = glm::vec4;
using ivec4 = glm::ivec4;
#define SHADOWLAB_CONST(type, name, value) constexpr type name = value;
#else
#define SHADOWLAB_CONST(type, name, value) const type name = value;
#endif

SHADOWLAB_CONST(int, kMaxLayers, 16)  // 8 light layers (cascades; a cube: 6) + 8 projectors
SHADOWLAB_CONST(int, kMaxLightLayers, 8)
SHADOWLAB_CONST(int, kMaxProjectors, 8)
SHADOWLAB_CONST(int, kMaxTaps, 64)           // the Poisson disc's points
SHADOWLAB_CONST(int, kProjectorChannels, 5)  // coverage, R, G, B, reverse
// Lloyd's m where the visible plane is edge-on to the light: the cap, and the singular values'
// ratio sMin / sMax below which the map-space Jacobian counts as singular (float rounding leaves
// an exactly edge-on plane's Jacobian at 1e-7 .. 1e-6 of its larger value, not 0). The same two
// values as compare.h's kFootprintCapPx and kFootprintSingularRatio (tests/raster_m_test.cpp).
SHADOWLAB_CONST(float, kFootprintCap, 1.0e6)
SHADOWLAB_CONST(float, kFootprintSingularRatio, 1.0e-5)
// Filterable maps: what 32-bit float moments hold of EVSM's warps (e^(2 c) < FLT_MAX with c <= 44).
SHADOWLAB_CONST(float, kEvsmMaxExponent, 42.0)

// The codes kFilter and kLightType take: kFilter<Name>, kLight<Name> from kinds.h's rows, and
// kLightNone for a scene rendered for its projectors only.
#define SHADOWLAB_ABI_FILTER(name, code, key, help) SHADOWLAB_CONST(int, kFilter##name, code)
SHADOWLAB_FILTERS(SHADOWLAB_ABI_FILTER)
#undef SHADOWLAB_ABI_FILTER
#define SHADOWLAB_ABI_LIGHT(name, code, key, help) SHADOWLAB_CONST(int, kLight##name, code)
SHADOWLAB_LIGHT_TYPES(SHADOWLAB_ABI_LIGHT)
#undef SHADOWLAB_ABI_LIGHT
SHADOWLAB_CONST(int, kLightNone, 3)

// Specialization constant ids of resolve.frag (each compiles a case's code out, see there).
SHADOWLAB_CONST(int, kSpecFilter, 0)          // a kFilter* code
SHADOWLAB_CONST(int, kSpecProjectorCount, 1)  // the scene's projectors
SHADOWLAB_CONST(int, kSpecCascaded, 2)        // 0/1
SHADOWLAB_CONST(int, kSpecBlend, 3)           // 0/1: a cascade blend band
SHADOWLAB_CONST(int, kSpecFloatDepth, 4)      // 0/1: the map's depth format is float
SHADOWLAB_CONST(int, kSpecLightType, 5)       // a kLight* code
SHADOWLAB_CONST(int, kSpecAffine, 6)          // 0/1: every light layer is orthographic
SHADOWLAB_CONST(int, kSpecAdaptive, 7)        // 0/1: bias.adaptive
// 0/1: the lookup pass (rasterizer.cpp, pass 4): the light's visibility alone into one R8
// attachment, the evidence and the projectors compiled out (compare/TIMINGS.md, lookup_gpu_ms).
// With kSpecCompact: the occluder's evidence pass over the pixels listed for it alone (vis,
// occluder, 2 * cascade + in_map into one RGBA32F attachment; raster.h, EvidenceRequest).
SHADOWLAB_CONST(int, kSpecLookupOnly, 8)
// 0/1: the evidence pass (rasterizer.cpp, pass 5): the resolve over a compacted list of pixels
// (EvidencePixels below), fragment k of a compact target resolving listed pixel k instead of the
// pixel under gl_FragCoord; the projectors compiled out (raster/METHODS.md, "Evidence on demand").
SHADOWLAB_CONST(int, kSpecCompact, 9)
// 0/1: the light layers' depth is the light's own, dot(P.lightDepth, (p, 1)), not texFromWorld's
// z / w (fit=tsm: MapLayer::lightDepth; the shadow pass writes it, id_light_depth.frag).
SHADOWLAB_CONST(int, kSpecLightDepth, 10)
// 0/1: bias.receiver_plane (the lookup's taps use the receiver plane's slope). Off, the lookup
// pass computes no slope at all (the full resolve still does, for bias_depth's slope term).
SHADOWLAB_CONST(int, kSpecReceiverPlane, 11)
// 0/1: bias.normal != 0 (the normal-offset lookup point). Off, the lookup point is the visible
// point itself: one projection instead of two.
SHADOWLAB_CONST(int, kSpecNormalOffset, 12)
// filter=pcf: filter.size (0 for the other filters, so they share pipelines). A compile-time loop
// bound lets the compiler unroll pcf's gathers; a sweep over filter.size compiles a pipeline per size.
SHADOWLAB_CONST(int, kSpecPcfSize, 13)
// 0/1: the planes pass (rasterizer.cpp, pass 3 at the first frame of an evidence group on demand):
// per pixel only the planes that depend on no bias or filter, m and 2 * cascade + in_map, into one
// attachment; the lookup, the evidence and the projectors compiled out.
SHADOWLAB_CONST(int, kSpecPlanesOnly, 14)
// 0/1: the lookup pass reads the pixel's visible point from the group's surface image (the point's
// map coordinates, or with cascades or a point light the point, and whether the light can reach
// it, written by the planes pass or the full resolve: resolve.frag's surfaceTexel) instead of the
// visibility buffer and the triangle's plane. Only where the lookup needs no normal: no normal
// offset, no receiver plane, no adaptive bias (rasterizer.cpp, lookupReadsSurface).
SHADOWLAB_CONST(int, kSpecSurface, 15)
// 0/1: the method's technique file reads ShadowQuery::planeSlope, which needs the triangle's normal:
// its lookup pass then reads the visibility buffer, not the surface image (rasterizer.cpp,
// lookupReadsSurface). resolve.frag does not declare it; it keys the pipelines.
SHADOWLAB_CONST(int, kSpecTechniqueNormal, 16)
// 0/1: the camera is orthographic (parallel rays, Params::rayC.w = 1): a constant, so a
// perspective camera's shader is the one it was before orthographic cameras.
SHADOWLAB_CONST(int, kSpecOrthoCamera, 17)
// A technique file's declared keys follow, kSpecCount + i (raster/src/technique_compiler.cpp).
SHADOWLAB_CONST(int, kSpecCount, 18)

// The descriptor set (set 0), one row per binding: X(Name, binding, kind). The kinds name
// Vulkan descriptor types (rasterizer.cpp maps them); the set layout, the pool and the writes
// are built from these rows. id.frag reads bindings 0..2 for its material tests.
#define SHADOWLAB_RESOLVE_BINDINGS(X)                                                              \
  X(TriangleMaterials, 0, StorageBuffer)   /* per triangle: its material index */                  \
  X(Materials, 1, StorageBuffer)           /* MaterialGpu per material */                          \
  X(AlphaTexels, 2, StorageBuffer)         /* alpha textures, concatenated */                      \
  X(Params, 3, UniformBuffer)              /* Params below */                                      \
  X(MapDepth, 4, CombinedImageSampler)     /* map depths, NEAREST */                               \
  X(MapShadow, 5, CombinedImageSampler)    /* map depths, LINEAR, compare LESS_OR_EQUAL */         \
  X(MapIds, 6, CombinedImageSampler)       /* map ids (global triangle + 1) */                     \
  X(CameraIds, 7, CombinedImageSampler)    /* the camera's visibility buffer */                    \
  X(TrianglePlanes, 8, UniformTexelBuffer) /* per triangle: its plane */                           \
  X(ProjectorTexels, 9, StorageBuffer)     /* projector images, RGB floats */                      \
  X(OutPlanes, 10, StorageBuffer)          /* the projector channels, one plane each */            \
  X(MomentsRows, 11, CombinedImageSampler) /* moments pass: the rows-blurred moments, NEAREST */   \
  X(Moments, 12, CombinedImageSampler)     /* the blurred moments per light layer, LINEAR */       \
  X(EvidencePixels, 13, StorageBuffer)     /* evidence pass: the listed pixels (x | y << 16) */    \
  X(ParamsLoops, 14, StorageBuffer)        /* Params again: its loop counts (ParamsLoops below) */ \
  X(Surface, 15, CombinedImageSampler)     /* the group's surface: (ray t, light reaches 1/-1/0) */
#define SHADOWLAB_ABI_BINDING(name, binding, kind) SHADOWLAB_CONST(int, kBinding##name, binding)
SHADOWLAB_RESOLVE_BINDINGS(SHADOWLAB_ABI_BINDING)
#undef SHADOWLAB_ABI_BINDING

// resolve.frag's uniform block (std140; every member is a vec4, ivec4 or mat4, or an array of
// them, so the C++ struct's natural layout is the std140 one: asserted below).
// (id.frag defines SHADOWLAB_ABI_NO_PARAMS: it reads only the material bindings.)
#if defined(__cplusplus) || !defined(SHADOWLAB_ABI_NO_PARAMS)
#ifdef __cplusplus
#define SHADOWLAB_BLOCK(name) struct name
#define SHADOWLAB_BLOCK_END(instance)
#else
#define SHADOWLAB_BLOCK(name) layout(std140, set = 0, binding = kBindingParams) uniform name
#define SHADOWLAB_BLOCK_END(instance) instance
#endif
SHADOWLAB_BLOCK(Params) {
  mat4 texFromWorld[kMaxLayers];  // world -> (u*w, v*w, depth*w, w), u,v in [0,1], v = 0 top
  vec4 layerInfo[kMaxLayers];     // x: world size of one texel per unit of w
  vec4 lightPosType;              // xyz position (w: the type, which the shader takes from kLightType)
  vec4 lightDirCos;               // xyz direction of travel, w: cos(cone / 2)
  vec4 cameraOrigin;              // xyz
  vec4 rayX;                      // unnormalized ray direction through image point (x, y):
  vec4 rayY;                      //   rayX * x + rayY * y + rayC (x, y in pixels)
  vec4 rayC;
  vec4 bias;       // x compare (depth), y normal (texels; on: kSpecNormalOffset), z receiver plane (0/1; the shader
                   // takes it from kSpecReceiverPlane), w poisson radius (texels)
  vec4 depthBias;  // x constant factor, y slope factor, z clamp, w r of the format (0: float format)
  ivec4 sizes;     // x map size, y light layers, z projector count, w pcf size (the shader reads kSpecPcfSize)
  ivec4 sizes2;    // x width, y height, z poisson taps, w reverse guard (0/1)
  ivec4 projector[kMaxProjectors];    // x first texel in projectorTexels, y width, z height, w layer
  vec4 poisson[kMaxTaps];             // xy: unit-disc offsets
  vec4 projectorPos[kMaxProjectors];  // xyz: world position
  vec4 cascadeView;                   // xyz fit camera forward (unit, world), w cascade count (0: not cascaded)
  vec4 cascadeFar[2];                 // C_1..C_8: far view depth of cascade 0..7, world units
  vec4 cascadeInfo;                   // x blend band (fraction of a cascade's depth range), y C_0,
                                      // z fit-camera view depth of the evaluation camera's origin
  vec4 moments;     // filterable maps: x vsm.min_variance, y vsm.bleed_reduction, z, w the EVSM exponents (clamped)
  vec4 moments2;    // x msm.moment_bias, y filter.blur (radius, texels)
  vec4 adaptive;    // adaptive depth bias (on: kSpecAdaptive): x bias.adaptive_epsilon (world units)
  vec4 lightDepth;  // kSpecLightDepth: the light layers' depth = dot(lightDepth, (p, 1))
  // The soft filters (filter=pcss, dpcf; raster/METHODS.md "Soft filters"). softTaps: x
  // pcss.blocker_taps, y pcss.filter_taps, z dpcf.taps, w rotate the taps per pixel (0/1; the
  // shader reads the counts through ParamsLoops). softInfo: x pcss.min_filter, y pcss.max_penumbra,
  // z dpcf.max_penumbra (texels).
  ivec4 softTaps;
  vec4 softInfo;
  // Per light layer, the light's size in that map's units (resolve_params.cpp, lightSizeInMap):
  // xy the penumbra radius in texels (u, v) per unit of the depth term, zw the perspective map's
  // depth linearization. Orthographic (zw = 0): radius = xy * (d_r - d_b), d the map depth (linear).
  // Perspective: z_lin = w / (d - z) (the view distance along the map's axis), radius =
  // xy * (z_r - z_b) / (z_b z_r). All zero for a hard light.
  vec4 lightSize[kMaxLightLayers];
}
SHADOWLAB_BLOCK_END(P);

// The loop counts of the filters and the blur, read through a second binding of the same Params
// buffer as a storage buffer (the same std140 bytes, explicit offsets). lavapipe (Mesa 22.3)
// inlines uniform-buffer values that bound a loop: at every draw after the descriptors or push
// constants are bound again it compiles a new shader variant with the values folded in, and
// never frees it (1 MB and ~1.3 ms per evidence-on-demand frame with filter=pcf or poisson,
// tests/raster_memory_test.cpp). A storage buffer's values are never inlined.
SHADOWLAB_CONST(int, kParamsSizesOffset, 1408)        // Params::sizes (then sizes2)
SHADOWLAB_CONST(int, kParamsCascadeViewOffset, 2720)  // Params::cascadeView
SHADOWLAB_CONST(int, kParamsMoments2Offset, 2800)     // Params::moments2
SHADOWLAB_CONST(int, kParamsSoftTapsOffset, 2848)     // Params::softTaps
#ifndef __cplusplus
layout(std140, set = 0, binding = kBindingParamsLoops) readonly buffer ParamsLoops {
  layout(offset = kParamsSizesOffset) ivec4 sizes;             // (w, the pcf size, is kSpecPcfSize)
  ivec4 sizes2;                                                // z: the Poisson taps
  layout(offset = kParamsCascadeViewOffset) vec4 cascadeView;  // w: the cascade count
  layout(offset = kParamsMoments2Offset) vec4 moments2;        // y: filter.blur (radius, texels)
  layout(offset = kParamsSoftTapsOffset) ivec4 softTaps;       // the soft filters' tap counts
}
PLoops;
#endif
#endif

// What a technique file's `float shadowVisibility(ShadowQuery q)` gets (raster/METHODS.md "Your own
// technique"): what an engine's lookup has, nothing it would not (no truth, no occluder ids). The
// maps are the globals `mapDepth` (sampler2DArray, NEAREST: texelFetch(mapDepth, ivec3(texel,
// q.layer), 0).r is a raw map depth) and `mapShadow` (sampler2DArrayShadow, LINEAR with compare
// LESS_OR_EQUAL: texture(mapShadow, vec4(uv, q.layer, depth)) is 1 where lit).
#if !defined(__cplusplus) && defined(SHADOWLAB_TECHNIQUE)
struct ShadowQuery {
  vec2 uv;          // the lookup point in the map, [0, 1] across it (v = 0 on the top row): st / mapSize
  vec2 st;          // the same in texels: texel (i, j) covers [i, i + 1) x [j, j + 1)
  int layer;        // the map layer (a cascade, a cube face): texelFetch's and texture's third coordinate
  float depth;      // the receiver's map depth at st after the configured biases (bias.compare or
                    // bias.adaptive, bias.normal's offset): lit where a stored depth >= it
  vec2 depthSlope;  // d(depth)/d(texel) the configured bias applies per tap (bias.receiver_plane or
                    // bias.adaptive on; else 0): a tap at texel t compares against
                    // depth + dot(depthSlope, vec2(t) + 0.5 - st), as the built-in filters do
  vec2 planeSlope;  // the receiver plane's d(depth)/d(texel), whatever the biases
  float mapSize;    // texels per side
  float texelSize;  // 1 / mapSize
  ivec2 pixel;      // the camera pixel (x right, y down): per-pixel noise
  int lightType;    // kLightDirectional, kLightSpot or kLightPoint
  // With a header line "// shadowlab: moments vsm|evsm2|evsm4|msm" (else 0; reading them without
  // one is an error): that filterable map's blurred moments (filter.blur) at uv, bilinear, as the
  // built-in filter reads them (the whole image: the global mapMoments, sampler2DArray, LINEAR);
  vec4 moments;
  vec4 momentKeys;   // (vsm.min_variance, vsm.bleed_reduction, evsm.exponent_pos, evsm.exponent_neg), exponents <= 42
  float momentBias;  // msm.moment_bias
};
#endif

#ifdef __cplusplus
// std140 offsets: a vec4 / ivec4 takes 16 bytes, a mat4 64, arrays of them have that stride.
static_assert(sizeof(vec4) == 16 && sizeof(ivec4) == 16 && sizeof(mat4) == 64);
static_assert(offsetof(Params, texFromWorld) == 0);
static_assert(offsetof(Params, layerInfo) == 64 * kMaxLayers);
static_assert(offsetof(Params, lightPosType) == 80 * kMaxLayers);
static_assert(offsetof(Params, lightDirCos) == offsetof(Params, lightPosType) + 16);
static_assert(offsetof(Params, cameraOrigin) == offsetof(Params, lightPosType) + 32);
static_assert(offsetof(Params, rayX) == offsetof(Params, lightPosType) + 48);
static_assert(offsetof(Params, rayY) == offsetof(Params, lightPosType) + 64);
static_assert(offsetof(Params, rayC) == offsetof(Params, lightPosType) + 80);
static_assert(offsetof(Params, bias) == offsetof(Params, lightPosType) + 96);
static_assert(offsetof(Params, depthBias) == offsetof(Params, lightPosType) + 112);
static_assert(offsetof(Params, sizes) == offsetof(Params, lightPosType) + 128);
static_assert(offsetof(Params, sizes2) == offsetof(Params, lightPosType) + 144);
static_assert(offsetof(Params, projector) == offsetof(Params, lightPosType) + 160);
static_assert(offsetof(Params, poisson) == offsetof(Params, projector) + 16 * kMaxProjectors);
static_assert(offsetof(Params, projectorPos) == offsetof(Params, poisson) + 16 * kMaxTaps);
static_assert(offsetof(Params, cascadeView) == offsetof(Params, projectorPos) + 16 * kMaxProjectors);
static_assert(offsetof(Params, cascadeFar) == offsetof(Params, cascadeView) + 16);
static_assert(offsetof(Params, cascadeInfo) == offsetof(Params, cascadeFar) + 32);
static_assert(offsetof(Params, moments) == offsetof(Params, cascadeInfo) + 16);
static_assert(offsetof(Params, moments2) == offsetof(Params, moments) + 16);
static_assert(offsetof(Params, adaptive) == offsetof(Params, moments2) + 16);
static_assert(offsetof(Params, lightDepth) == offsetof(Params, adaptive) + 16);
static_assert(offsetof(Params, softTaps) == offsetof(Params, lightDepth) + 16);
static_assert(offsetof(Params, softInfo) == offsetof(Params, softTaps) + 16);
static_assert(offsetof(Params, lightSize) == offsetof(Params, softInfo) + 16);
static_assert(offsetof(Params, sizes) == kParamsSizesOffset && offsetof(Params, moments2) == kParamsMoments2Offset &&
              offsetof(Params, cascadeView) == kParamsCascadeViewOffset &&
              offsetof(Params, softTaps) == kParamsSoftTapsOffset);
static_assert(sizeof(Params) == 2848 + 32 + 16 * kMaxLightLayers,
              "std140 size of resolve.frag's Params (glslangValidator -q reports it)");
static_assert(2 * 4 >= kMaxLightLayers, "cascadeFar holds one far split per light layer");
static_assert(kMaxLightLayers + kMaxProjectors == kMaxLayers);
}  // namespace shadowlab::raster::abi
#endif

#ifdef SHADOWLAB_BLOCK
#undef SHADOWLAB_BLOCK
#undef SHADOWLAB_BLOCK_END
#endif
#undef SHADOWLAB_CONST
#endif
