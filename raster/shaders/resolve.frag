#version 460
// Camera pass, part 2: per pixel, from the visibility buffer (global triangle + 1) of part 1.
// The visible point is the intersection of the pixel-center camera ray with the visible
// triangle's plane (the reference's hit point up to float rounding), and every derivative
// (texel footprint m, receiver plane) is taken analytically on that plane instead of from
// 2x2-quad differences, so triangle edges do not smear neighbouring planes into each other.
// Writes the light's channels into two color attachments (outA, outB) and each
// projector's channels as float planes into `outPlanes`.
// A full-screen fragment shader rather than a compute shader: lavapipe's fragment path is its
// fast one (tiled, multi-threaded), its compute dispatch costs ~0.2 us per invocation even empty.
// One fragment per pixel. Attachments rather than storage-buffer stores for the per-pixel
// outputs: on lavapipe a store at a per-pixel address is a loop over the SIMD lanes.

#extension GL_GOOGLE_include_directive : require
#include "shadowlab/raster/resolve_abi.h"

// Specialized per filter so lavapipe compiles straight-line code for the cheap filters.
layout(constant_id = kSpecFilter) const int kFilter = kFilterNone;
// The scene's projector count: lavapipe runs every branch of a shader masked, so an empty
// projector loop still costs unless it is compiled out.
layout(constant_id = kSpecProjectorCount) const int kProjectorCount = 0;
// Cascades (directional light, fit=cascades), a blend band, a float depth format: off, their
// code is compiled out (lavapipe would run it masked for every pixel).
layout(constant_id = kSpecCascaded) const bool kCascaded = false;
layout(constant_id = kSpecBlend) const bool kBlend = false;
layout(constant_id = kSpecFloatDepth) const bool kFloatDepth = false;
// The light's type (kLightDirectional, kLightSpot, kLightPoint, kLightNone): the other types'
// code compiled out.
layout(constant_id = kSpecLightType) const int kLightType = kLightDirectional;
// Every light layer is affine (orthographic: texFromWorld's last row is (0, 0, 0, 1)), so w = 1
// and the divisions by it fold away; the results are the same bits.
layout(constant_id = kSpecAffine) const bool kAffine = false;
layout(constant_id = kSpecOrthoCamera) const bool kOrthoCamera = false;
// The light layers' depth is the light's own (fit=tsm): depth = dot(P.lightDepth, (p, 1)), not
// texFromWorld's z / w; u, v and w still come from texFromWorld.
layout(constant_id = kSpecLightDepth) const bool kLightDepth = false;
// bias.adaptive (adaptiveEpsilon): off, its code is compiled out.
layout(constant_id = kSpecAdaptive) const bool kAdaptive = false;
// bias.receiver_plane and bias.normal != 0 (P.bias.z, P.bias.y): off, the lookup uses no slope and
// looks up the visible point itself, and the lookup pass computes neither the slope nor a second
// projection (as uniform-buffer tests, lavapipe ran both for every pixel). The same bits: with
// bias.normal = 0 the offset point is the visible point, and a zero slope adds zero.
layout(constant_id = kSpecReceiverPlane) const bool kReceiverPlane = false;
layout(constant_id = kSpecNormalOffset) const bool kNormalOffset = false;
layout(constant_id = kSpecPcfSize) const int kPcfSize = 1;
// The lookup pass: what an engine pays for the method, the same lookup and filter as the resolve
// (shadeLight below) with only the visibility written, 1 byte per pixel into outA's R8 attachment;
// the unread evidence is dead code the compiler removes.
layout(constant_id = kSpecLookupOnly) const bool kLookupOnly = false;
// The evidence pass (evidence on demand): fragment k of a compact target resolves the k-th listed
// pixel (evidencePixels[first + k], x | y << 16) instead of the pixel under it. Nothing here depends on
// the 2x2 quad but hw2x2's implicit LOD, which selects nothing (see hwVis in shadeLight), so the
// listed pixels get the full resolve's bits (tests/raster_evidence_test.cpp).
layout(constant_id = kSpecCompact) const bool kCompact = false;
// The planes pass (the first frame of an evidence group on demand): m and 2 * cascade + in_map
// alone, as outA.x and outA.y (the full resolve's outA.w and outB.w), the rest dead code.
layout(constant_id = kSpecPlanesOnly) const bool kPlanesOnly = false;
// The lookup pass of a method that needs no normal: the visible point from the group's surface
// image (the planes pass or the full resolve writes it, surfaceTexel) rather than from the
// visibility buffer and the triangle's plane, one fetch instead of two, like a deferred renderer
// reconstructing the point from its depth buffer. With one map layer (kProjectedSurface) the
// surface holds the point's map coordinates (u, v, depth) as the writer computed them, bit for bit
// what the lookup would compute from the point: the lookup reads them and projects nothing.
// Cascades and point lights pick the layer from the point: their surface holds the point itself,
// as the writer computed it.
layout(constant_id = kSpecSurface) const bool kSurface = false;
// A technique file (method key technique; raster/METHODS.md "Your own technique"): compiled at run
// time with SHADOWLAB_TECHNIQUE defined (raster/src/technique_compiler.cpp), its shadowVisibility()
// replaces filterVisibility wherever the built-in filters would run (filter is none then).
#ifdef SHADOWLAB_TECHNIQUE
const bool kTechnique = true;
#else
const bool kTechnique = false;
#endif

// Params P (binding kBindingParams) comes from resolve_abi.h.
layout(set = 0, binding = kBindingMapDepth) uniform sampler2DArray mapDepth;         // NEAREST, raw depth
layout(set = 0, binding = kBindingMapShadow) uniform sampler2DArrayShadow mapShadow;  // LINEAR, compare LESS_OR_EQUAL
layout(set = 0, binding = kBindingMapIds) uniform usampler2DArray mapIds;
// Filterable maps: the blurred moments of each light layer (moments_rows/cols.frag), LINEAR.
layout(set = 0, binding = kBindingMoments) uniform sampler2DArray momentsMap;
layout(set = 0, binding = kBindingCameraIds) uniform usampler2D cameraIds;
// The group's surface (kSurface; surfaceTexel says what it holds).
layout(set = 0, binding = kBindingSurface) uniform sampler2D surfaceMap;

// Per triangle (at its global index + 1, as in the id attachments; texel 0 a placeholder), its
// plane relative to the camera origin o: (n, dot(n, v0 - o)), n the unit normal
// (v1 - v0) x (v2 - v0), computed in double on the CPU. A texel buffer: on lavapipe a
// storage-buffer load at a per-pixel address is a bounds-checked loop over the SIMD lanes, a
// texel fetch one gather; and one fetch per pixel, since each costs about as much as the rest of
// the arithmetic.
layout(set = 0, binding = kBindingTrianglePlanes) uniform samplerBuffer trianglePlanes;
layout(std430, set = 0, binding = kBindingProjectorTexels) readonly buffer ProjectorTexels { float projectorTexels[]; };
layout(std430, set = 0, binding = kBindingOutPlanes) writeonly buffer OutPlanes { float outPlanes[]; };
layout(std430, set = 0, binding = kBindingEvidencePixels) readonly buffer EvidencePixels { uint evidencePixels[]; };
// The evidence pass's list: how many pixels, the compact target's width and where the list starts
// in evidencePixels (the shadow pass's push block: a mat4, then these three).
layout(push_constant) uniform Push {
  layout(offset = 64) uint count;
  uint compactWidth;
  uint first;
} pc;

// The rasterizer splits these into the frame's channels (rasterizer.cpp, readback).
layout(location = 0) out vec4 outA;  // vis, receiver_depth, map_depth, m
layout(location = 1) out vec4 outB;  // bias_depth, bias_world, occluder (id), 2 * cascade + in_map
                                     // (the planes pass: the surface, ray t and light reaches)
// Filterable maps only (the pipeline has this third attachment for them alone): the moments'
// evidence at the lookup: mean depth, variance, the bound before the bleed cut.
layout(location = 2) out vec4 outC;
// The group's surface (kSurface's image, surfaceTexel), which the full resolve writes for the lookup
// after it, as the next attachment: outC's without moments, outD's with them (the planes pass:
// outB's).
layout(location = 3) out vec4 outD;

// The group's surface holds map coordinates (one layer: no cascades, not a point light's cube).
const bool kProjectedSurface = !kCascaded && kLightType != kLightPoint && kLightType != kLightNone;

const bool kMomentFilter =
    kFilter == kFilterVsm || kFilter == kFilterEvsm2 || kFilter == kFilterEvsm4 || kFilter == kFilterMsm;

// The pixel's visible surface: the camera ray through the pixel center meets the visible
// triangle's plane at p.
struct Surface {
  bool hit;       // a triangle covers the pixel (kSurface: and the light reaches its visible side)
  bool covered;   // a triangle covers the pixel
  vec3 uvz;       // kSurface with kProjectedSurface: the point's map coordinates (the rest unread;
  bool inMap;     //   without it p alone) and whether they lie in the map (LayerHit's)
  vec4 plane;     // the triangle's plane (n, dot(n, v0 - camera origin))
  vec3 dir;       // the (unnormalized) ray direction through the pixel center
  float t;        // p = camera origin + dir * t
  vec3 p;         // the visible point, world
  vec3 normal;    // the plane's unit normal, facing the camera
  vec3 e1;        // a unit tangent of the plane
};

// One map layer and the projection into it.
struct Layer {
  int index;
  mat4 texFromWorld;  // P.texFromWorld[index], fetched once: dynamic UBO indexing is a gather on CPUs
  float size;         // texels per side
};

// Where a point looks a layer up (after the normal offset): what the filters read.
struct Lookup {
  Layer layer;
  vec2 st;     // lookup position in texels
  float ref;   // reference depth at st (receiver depth - compare bias)
  vec2 slope;  // receiver plane: d(depth)/d(texel u, v), zero when bias.receiver_plane is off
  vec2 planeSlope;  // the receiver plane's d(depth)/d(texel u, v) whatever the bias (techniques read it)
};

// A point's lookup in a light layer with everything derived on the way (normal offset, plane).
struct LayerHit {
  Lookup lookup;
  vec4 tP;           // project(p)
  vec4 tQ;           // project(q), q the normal-offset lookup point
  vec3 uvz;          // tQ's (u, v, depth)
  float texelWorld;  // world size of one texel at p
  bool inMap;        // q projects in front of the light, inside the map
  vec2 planeSlope;   // the receiver plane's slope, whether the bias uses it or not
};

Layer layerAt(int index) { return Layer(index, P.texFromWorld[index], float(P.sizes.x)); }

// An orthographic camera (kSpecOrthoCamera; rayC.w = 1, resolve_params.cpp): parallel rays d = rayC from the points
// cameraOrigin + rayX x + rayY y of the plane through the camera; else rays from cameraOrigin.
bool orthoCamera() { return kOrthoCamera; }
vec3 rayOffset(vec2 pixel) { return P.rayX.xyz * pixel.x + P.rayY.xyz * pixel.y; }
vec3 rayThrough(vec2 pixel) {
  return orthoCamera() ? P.rayC.xyz : P.rayX.xyz * pixel.x + P.rayY.xyz * pixel.y + P.rayC.xyz;
}
// Where the camera ray origin + d t meets a plane (n, dot(n, v0 - cameraOrigin)): its t, and the point.
float planeT(vec3 d, vec4 plane, vec2 pixel) {
  return orthoCamera() ? (plane.w - dot(plane.xyz, rayOffset(pixel))) / dot(d, plane.xyz) : plane.w / dot(d, plane.xyz);
}
vec3 rayPoint(vec3 d, float t, vec2 pixel) {
  return orthoCamera() ? P.cameraOrigin.xyz + rayOffset(pixel) + d * t : P.cameraOrigin.xyz + d * t;
}

// The layer's homogeneous coordinates of a point (u w, v w, depth w, w); the first, second and
// fourth move by dirMap(v) per unit of v, and so does the third unless kLightDepth:
// project(p + v) = projectStep(l, project(p), v).
vec4 project(Layer l, vec3 pWorld) {
  vec4 t = l.texFromWorld * vec4(pWorld, 1.0);
  if (kAffine) t.w = 1.0;
  if (kLightDepth) t.z = dot(P.lightDepth, vec4(pWorld, 1.0)) * t.w;
  return t;
}
vec4 dirMap(Layer l, vec3 v) {
  vec4 t = l.texFromWorld[0] * v.x + l.texFromWorld[1] * v.y + l.texFromWorld[2] * v.z;
  if (kAffine) t.w = 0.0;
  return t;
}
// kLightDepth: depth * w is the light depth (affine) times w (affine), not affine itself.
vec4 projectStep(Layer l, vec4 t, vec3 v) {
  vec4 r = t + dirMap(l, v);
  if (kLightDepth) r.z = (t.z / t.w + dot(P.lightDepth.xyz, v)) * r.w;
  return r;
}

// Lit (1) when the stored depth is not in front of the reference depth.
float tap(Layer l, ivec2 texel, float depthRef) {
  ivec2 c = clamp(texel, ivec2(0), ivec2(int(l.size) - 1));
  return texelFetch(mapDepth, ivec3(c, l.index), 0).r >= depthRef ? 1.0 : 0.0;
}

float refAt(Lookup L, ivec2 texel) { return L.ref + dot(L.slope, vec2(texel) + 0.5 - L.st); }

// The 2x2 texels t, t + (1, 0), t + (0, 1), t + (1, 1) in one fetch: textureGather at their shared
// corner returns them as (w, z, x, y) (Vulkan's order), clamped at the map's edge like tap()'s.
// On lavapipe every texel fetch is a call; one gather costs about what one texelFetch does.
vec4 gather4(Layer l, ivec2 t) {
  return textureGather(mapDepth, vec3((vec2(t) + 1.0) / l.size, float(l.index)));
}
float lit(Lookup L, float stored, ivec2 texel) { return stored >= refAt(L, texel) ? 1.0 : 0.0; }

// The texel under the lookup, clamped to the map.
ivec2 centerTexel(Lookup L) { return clamp(ivec2(floor(L.st)), ivec2(0), ivec2(int(L.layer.size) - 1)); }

// ---- Filterable maps (raster/METHODS.md "Filterable maps") ----
// What a moments lookup found: the visibility (the bound after the bleed cut) and its evidence.
struct MomentLookup {
  float vis;
  float mean;      // mean depth of the footprint (normalized map depth; EVSM: ln(E[e^(c+ z')]) / c+ mapped back)
  float variance;  // the variance the bound used (vsm, msm: depth^2; evsm: of the positive warp)
  float bound;     // Chebyshev's (vsm, evsm) or the Hamburger 4-moment (msm) upper bound of the lit fraction
};

// One-sided Chebyshev (Cantelli): P(z >= t) <= variance / (variance + (t - mean)^2) for t > mean.
float chebyshevBound(float mean, float meanSq, float t, float minVariance, out float variance) {
  variance = max(meanSq - mean * mean, minVariance);
  float d = t - mean;
  return t <= mean ? 1.0 : variance / (variance + d * d);
}

// Peters & Klein 2015 (Moment Shadow Mapping, I3D), Algorithm 2: the Hamburger 4-moment
// reconstruction's bound of the lit fraction at depth t from moments b = (z, z^2, z^3, z^4) pulled
// towards (0.5, 0.5, 0.5, 0.5) by the moment bias (the paper's alpha).
float hamburger4(vec4 moments, float t, float momentBias) {
  vec4 b = mix(moments, vec4(0.5), momentBias);
  float z0 = t;
  // Cholesky factorization of the Hankel matrix of b, only its non-trivial products.
  float L32D22 = fma(-b.x, b.y, b.z);
  float D22 = fma(-b.x, b.x, b.y);
  float squaredDepthVariance = fma(-b.y, b.y, b.w);
  float D33D22 = dot(vec2(squaredDepthVariance, -L32D22), vec2(D22, L32D22));
  float InvD22 = 1.0 / D22;
  float L32 = L32D22 * InvD22;
  // The scaled inverse image of (1, z0, z0^2): forward substitution, scaling, back substitution.
  vec3 c = vec3(1.0, z0, z0 * z0);
  c.y -= b.x;
  c.z -= b.y + L32 * c.y;
  c.y *= InvD22;
  c.z *= D22 / D33D22;
  c.y -= L32 * c.z;
  c.x -= dot(c.yz, b.xy);
  // The roots z1 <= z2 of c.x + c.y z + c.z z^2: the other two support points.
  float p = c.y / c.z, q = c.x / c.z;
  float r = sqrt(max(p * p * 0.25 - q, 0.0));
  float z1 = -p * 0.5 - r, z2 = -p * 0.5 + r;
  vec4 sw = z2 < z0 ? vec4(z1, z0, 1.0, 1.0) : (z1 < z0 ? vec4(z0, z1, 0.0, 1.0) : vec4(0.0));
  float quotient = (sw.x * z2 - b.x * (sw.x + z2) + b.y) / ((z2 - sw.y) * (z0 - z1));
  float shadow = clamp(sw.z + sw.w * quotient, 0.0, 1.0);
  return 1.0 - shadow;
}

float linstep(float lo, float hi, float v) { return clamp((v - lo) / (hi - lo), 0.0, 1.0); }

MomentLookup momentLookup(Lookup L) {
  // Bilinear (the sampler) over the blurred moments, at the lookup; explicit LOD 0 (one level).
  vec4 mo = textureLod(momentsMap, vec3(L.st / L.layer.size, float(L.layer.index)), 0.0);
  float t = L.ref, minVariance = P.moments.x;
  MomentLookup r;
  if (kFilter == kFilterMsm) {
    r.mean = mo.x;
    r.variance = mo.y - mo.x * mo.x;
    r.bound = hamburger4(mo, t, P.moments2.x);
  } else if (kFilter == kFilterVsm) {
    r.mean = mo.x;
    r.bound = chebyshevBound(mo.x, mo.y, t, minVariance, r.variance);
  } else {
    // EVSM: the receiver warped like the map; the variance floor scaled by the warp's slope at t.
    float cPos = P.moments.z, cNeg = P.moments.w;
    float tw = 2.0 * clamp(t, 0.0, 1.0) - 1.0;
    float tPos = exp(cPos * tw);
    r.bound = chebyshevBound(mo.x, mo.y, tPos, minVariance * (cPos * tPos) * (cPos * tPos), r.variance);
    if (kFilter == kFilterEvsm4) {
      float tNeg = -exp(-cNeg * tw), varianceNeg;
      r.bound = min(r.bound, chebyshevBound(mo.z, mo.w, tNeg, minVariance * (cNeg * tNeg) * (cNeg * tNeg), varianceNeg));
    }
    r.mean = 0.5 * (log(max(mo.x, 1e-30)) / cPos + 1.0);
  }
  r.vis = linstep(P.moments.y, 1.0, r.bound);
  return r;
}

// The pixel being resolved (the listed one in the evidence pass): a technique's per-pixel noise.
ivec2 gPixel = ivec2(0);

#ifdef SHADOWLAB_TECHNIQUE
// The user's file (the includer hands it over with its own line numbers), after its declared keys
// as specialization constants technique_<name> (ids kSpecCount + i).
#include "shadowlab/technique"
// The lookup as an engine's shader would see it (ShadowQuery, resolve_abi.h); the result clamped to
// [0, 1] (the same bits for every value inside).
float techniqueVisibility(Lookup L) {
  ShadowQuery q;
  q.uv = L.st / L.layer.size;
  q.st = L.st;
  q.layer = L.layer.index;
  q.depth = L.ref;
  q.depthSlope = L.slope;
  q.planeSlope = L.planeSlope;
  q.mapSize = L.layer.size;
  q.texelSize = 1.0 / L.layer.size;
  q.pixel = gPixel;
  q.lightType = kLightType;
  // A file with a moments line (kFilter is then that filterable map's): its moments at the lookup,
  // as the built-in filter reads them, and the keys its reconstruction takes.
  q.moments = kMomentFilter ? textureLod(momentsMap, vec3(q.uv, float(L.layer.index)), 0.0) : vec4(0.0);
  q.momentKeys = kMomentFilter ? P.moments : vec4(0.0);
  q.momentBias = kMomentFilter ? P.moments2.x : 0.0;
  return clamp(shadowVisibility(q), 0.0, 1.0);
}
#endif

// ---- Soft filters (raster/METHODS.md "Soft filters"): pcss and dpcf, from the light's size ----
// Interleaved gradient noise (Jimenez 2014): an angle per pixel that differs between neighbours,
// the pixel alone deciding it (the same bits in every pass and in the evidence pass).
float softFilterNoise(vec2 pixel) { return fract(52.9829189 * fract(dot(pixel, vec2(0.06711056, 0.00583715)))); }

// The Poisson taps' rotation: per pixel with pcss.rotate / dpcf.rotate (P.softTaps.w), else none.
mat2 softRotation() {
  if (P.softTaps.w == 0) return mat2(1.0);
  float a = 6.28318531 * softFilterNoise(vec2(gPixel));
  float c = cos(a), s = sin(a);
  return mat2(c, s, -s, c);
}

// The penumbra radius in texels (u, v) that blockers at map depth dB cast on a receiver at map
// depth dR, from the light's size in this layer's units (P.lightSize, resolve_params.cpp
// lightSizeInMap). A directional light's map is orthographic and its depth linear: radius =
// size * (dR - dB). A spot's or point's map is perspective: the depths linearized to view
// distances z = B / (d - A), radius = size * (zR - zB) / (zB zR). dB = 0 is the map's near plane:
// the blocker-search region (the widest penumbra any blocker in front of the receiver casts).
vec2 softPenumbraTexels(vec4 lightSize, float dR, float dB) {
  if (kLightType == kLightDirectional) return lightSize.xy * max(dR - dB, 0.0);
  float zR = lightSize.w / (dR - lightSize.z), zB = lightSize.w / (dB - lightSize.z);
  return lightSize.xy * (max(zR - zB, 0.0) / (zB * zR));
}

// The stored depth of texel t, clamped to the map like tap()'s.
float softStoredDepth(Layer l, ivec2 t) {
  return texelFetch(mapDepth, ivec3(clamp(t, ivec2(0), ivec2(int(l.size) - 1)), l.index), 0).r;
}

// One blocker search over `taps` Poisson taps of radius `radius` texels: the taps whose stored depth
// lies in front of their reference (receiver-plane slope per tap as refAt applies it), their count
// and the sum of their depths.
vec2 softBlockerSearch(Lookup L, mat2 rotation, vec2 radius, int taps) {
  float blockers = 0.0, depthSum = 0.0;
  for (int i = 0; i < taps; ++i) {
    ivec2 t = ivec2(floor(L.st + rotation * (P.poisson[i].xy * radius)));
    float z = softStoredDepth(L.layer, t);
    if (z < refAt(L, t)) {
      blockers += 1.0;
      depthSum += z;
    }
  }
  return vec2(blockers, depthSum);
}

// PCSS (Fernando 2005): search the blocker region for blockers (none: lit), their mean depth gives
// the penumbra radius, a Poisson PCF over that radius the visibility. Both radii clamped to
// [pcss.min_filter, pcss.max_penumbra] (a hard light's kernel is pcss.min_filter). The cap is
// pcss.max_penumbra texels of a 512 map, scaled with the layer's size: it bounds the same share
// of the map whatever its resolution, so a sharper map resolves the same penumbra instead of
// cutting a wider (in texels) one short.
float pcssVisibility(Lookup L) {
  vec4 lightSize = P.lightSize[L.layer.index];
  mat2 rotation = softRotation();
  vec2 lo = vec2(P.softInfo.x), hi = vec2(max(P.softInfo.x, P.softInfo.y * (L.layer.size / 512.0)));
  vec2 found = softBlockerSearch(L, rotation, clamp(softPenumbraTexels(lightSize, L.ref, 0.0), lo, hi), PLoops.softTaps.x);
  if (found.x == 0.0) return 1.0;
  vec2 radius = clamp(softPenumbraTexels(lightSize, L.ref, found.y / found.x), lo, hi);
  int taps = PLoops.softTaps.y;
  float sum = 0.0;
  for (int i = 0; i < taps; ++i) {
    ivec2 t = ivec2(floor(L.st + rotation * (P.poisson[i].xy * radius)));
    sum += tap(L.layer, t, refAt(L, t));
  }
  return sum / float(taps);
}

// DPCF's hardened kernel: the occluded fraction pushed towards 0 or 1 by a cubic,
// 1/2 + 1/2 sign(y) (1 - (1 - |y|)^3) with y = 2 p - 1 (0, 1/2 and 1 stay where they are).
float dpcfHardenedKernel(float p) {
  float y = 2.0 * p - 1.0, a = 1.0 - abs(y);
  return 0.5 + 0.5 * sign(y) * (1.0 - a * a * a);
}

// DPCF (Filament, after "Shadows of Cold War"): one kernel of dpcf.taps, no second pass. Its
// radius is the penumbra of a blocker whose penumbra ratio is 1 (halfway between the map's near
// plane and the receiver: a perspective map's R size / z_r, Filament's bulb radius over z), clamped
// to [1, dpcf.max_penumbra] texels. The occluded share is blended from the hardened kernel towards
// plain PCF by the saturated penumbra ratio (z_r - z_b) / z_b of the blockers' mean depth, in the
// map's linear depth (Filament's (z_b - z_r) / (1 - z_b) in reversed Z): 0 at a contact (hard).
float dpcfVisibility(Lookup L) {
  vec4 lightSize = P.lightSize[L.layer.index];
  float zR = kLightType == kLightDirectional ? L.ref : lightSize.w / (L.ref - lightSize.z);
  vec2 kernel = kLightType == kLightDirectional ? lightSize.xy * (0.5 * L.ref) : lightSize.xy / zR;
  vec2 radius = clamp(kernel, vec2(1.0), vec2(P.softInfo.z));
  int taps = PLoops.softTaps.z;
  vec2 found = softBlockerSearch(L, softRotation(), radius, taps);
  if (found.x == 0.0) return 1.0;
  float dB = found.y / found.x;
  float zB = kLightType == kLightDirectional ? dB : lightSize.w / (dB - lightSize.z);
  float ratio = clamp((zR - zB) / max(zB, 1e-30), 0.0, 1.0);
  float occluded = found.x / float(taps);
  return 1.0 - mix(dpcfHardenedKernel(occluded), occluded, ratio);
}

// The filters other than none (whose one comparison the caller makes with its own fetch).
float filterVisibility(Lookup L) {
#ifdef SHADOWLAB_TECHNIQUE
  return techniqueVisibility(L);
#endif
  if (kMomentFilter) return momentLookup(L).vis;
  ivec2 center = ivec2(floor(L.st));
  if (kFilter == kFilterHw2x2) {
    // The hardware blends four comparisons; the receiver plane cannot be applied per tap.
    // (shadeLight looks up the pixel's own layer with texture(), see hwVis there; this is
    // the blend band's lookup.)
    return textureGrad(mapShadow, vec4(L.st / L.layer.size, float(L.layer.index), L.ref), vec2(0.0), vec2(0.0));
  } else if (kFilter == kFilterBilinear4) {
    vec2 s = L.st - 0.5;
    ivec2 i0 = ivec2(floor(s));
    vec2 f = s - floor(s);
    vec4 g = gather4(L.layer, i0);
    float v00 = lit(L, g.w, i0), v10 = lit(L, g.z, i0 + ivec2(1, 0));
    float v01 = lit(L, g.x, i0 + ivec2(0, 1)), v11 = lit(L, g.y, i0 + ivec2(1, 1));
    return mix(mix(v00, v10, f.x), mix(v01, v11, f.x), f.y);
  } else if (kFilter == kFilterPcf) {
    // The (2h + 1)^2 taps as 2x2 gathers; the last row and column of gathers use half their
    // texels. The sum counts whole taps, so its order does not change it.
    const int h = kPcfSize / 2;  // a constant: the loops unroll (never a uniform-buffer bound: ParamsLoops)
    float sum = 0.0;
    for (int by = -h; by <= h; by += 2)
      for (int bx = -h; bx <= h; bx += 2) {
        ivec2 t = center + ivec2(bx, by);
        vec4 g = gather4(L.layer, t);
        bool right = bx < h, down = by < h;
        sum += lit(L, g.w, t);
        sum += right ? lit(L, g.z, t + ivec2(1, 0)) : 0.0;
        sum += down ? lit(L, g.x, t + ivec2(0, 1)) : 0.0;
        sum += right && down ? lit(L, g.y, t + ivec2(1, 1)) : 0.0;
      }
    float n = float(2 * h + 1);
    return sum / (n * n);
  } else if (kFilter == kFilterPoisson) {
    int taps = PLoops.sizes2.z;
    float sum = 0.0;
    for (int i = 0; i < taps; ++i) {
      ivec2 t = ivec2(floor(L.st + P.poisson[i].xy * P.bias.w));
      sum += tap(L.layer, t, refAt(L, t));
    }
    return sum / float(taps);
  } else if (kFilter == kFilterPcss) {
    return pcssVisibility(L);
  } else if (kFilter == kFilterDpcf) {
    return dpcfVisibility(L);
  }
  return tap(L.layer, center, refAt(L, center));
}

// The receiver's plane in map space, from two tangent points one texel away: the same
// (dz/du, dz/dv) the dFdx/dFdy solve yields, without its singularity at grazing views.
// tQ = project(q); the tangent points' coordinates follow from it by linearity.
vec2 planeSlope(Layer l, vec4 tQ, vec3 normal, vec3 e1, float texelWorld) {
  vec3 e2 = cross(normal, e1);
  vec4 t1 = projectStep(l, tQ, e1 * texelWorld), t2 = projectStep(l, tQ, e2 * texelWorld);
  float gSize = l.size;
  vec3 m0 = vec3(tQ.xy / tQ.w * gSize, tQ.z / tQ.w), m1 = vec3(t1.xy / t1.w * gSize, t1.z / t1.w),
       m2 = vec3(t2.xy / t2.w * gSize, t2.z / t2.w);
  vec2 a1 = m1.xy - m0.xy, a2 = m2.xy - m0.xy;
  float det = a1.x * a2.y - a1.y * a2.x;
  return abs(det) > 1e-12 ? vec2((m1.z - m0.z) * a2.y - (m2.z - m0.z) * a1.y,
                                 (m2.z - m0.z) * a1.x - (m1.z - m0.z) * a2.x) / det
                          : vec2(0.0);
}

// One step r of the map's depth format at a depth: the fixed formats' (P.depthBias.w), a float
// format's ulp there (Vulkan's r for D32F).
float depthResolution(float depth) { return kFloatDepth ? exp2(floor(log2(max(depth, 1e-30))) - 23.0) : P.depthBias.w; }

vec3 towardsLight(vec3 p) {
  return kLightType == kLightDirectional ? -P.lightDirCos.xyz : normalize(P.lightPosType.xyz - p);
}

// Adaptive depth bias (Dou, Yan, Kerzner, Dai, Wyman 2014): a tap's reference is the depth at
// which the light's ray through its texel centre meets the receiver's tangent plane. A projective
// map keeps that plane a plane, z = depth(q) + planeSlope . (texel centre - st), so refAt with the
// receiver plane's slope is that intersection without an inverse matrix. Less the epsilon: the
// scene-scale bias.adaptive_epsilon (world units along the light ray, here in map depth at q) plus
// one step of the depth format (the stored depth's rounding; the paper's precision term).
float adaptiveEpsilon(Layer l, vec3 q, vec4 tQ, float depthQ) {
  vec4 tE = projectStep(l, tQ, towardsLight(q) * P.adaptive.x);
  return max(depthQ - tE.z / tE.w, 0.0) + depthResolution(depthQ);
}

// Whether a point projected to t (map coordinates uvz = t.xyz / t.w) lies in front of the light,
// inside the map.
bool inMapAt(vec4 t, vec3 uvz) {
  return t.w > 0.0 && all(greaterThanEqual(uvz.xy, vec2(0.0))) && all(lessThanEqual(uvz.xy, vec2(1.0)));
}

// The one lookup of a surface point in a light layer, for the pixel's own layer and for the next
// cascade of a blend band: the normal offset, the projection, the receiver plane.
LayerHit lookUp(int layerIndex, Surface s) {
  LayerHit h;
  Layer l = layerAt(layerIndex);
  h.tP = project(l, s.p);
  h.texelWorld = P.layerInfo[layerIndex].x * abs(h.tP.w);
  vec3 q = kNormalOffset ? s.p + s.normal * (P.bias.y * h.texelWorld) : s.p;  // normal-offset lookup point
  h.tQ = kNormalOffset ? project(l, q) : h.tP;
  h.uvz = h.tQ.xyz / h.tQ.w;
  h.inMap = inMapAt(h.tQ, h.uvz);
  h.planeSlope = planeSlope(l, h.tQ, s.normal, s.e1, h.texelWorld);
  float ref = kAdaptive ? h.uvz.z - adaptiveEpsilon(l, q, h.tQ, h.uvz.z) : h.uvz.z - P.bias.x;
  h.lookup = Lookup(l, h.uvz.xy * l.size, ref, kReceiverPlane || kAdaptive ? h.planeSlope : vec2(0.0), h.planeSlope);
  return h;
}

// lookUp's answer from the group's surface (kSurface with kProjectedSurface: no normal offset, no
// receiver plane, no adaptive bias, nothing that reads the plane's slope): the map coordinates
// and inMap as the writer's lookUp computed them; what they do not give only feeds the evidence,
// which the lookup does not write.
LayerHit surfaceHit(int layerIndex, Surface s) {
  LayerHit h;
  Layer l = layerAt(layerIndex);
  h.uvz = s.uvz;
  h.inMap = s.inMap;
  h.tP = vec4(s.uvz, 1.0);
  h.tQ = h.tP;
  h.texelWorld = 0.0;
  h.planeSlope = vec2(0.0);
  h.lookup = Lookup(l, h.uvz.xy * l.size, h.uvz.z - P.bias.x, vec2(0.0), vec2(0.0));
  return h;
}

// The blend band's lookup (the next cascade): filtered like the pixel's own, policy lit outside
// the map; hw2x2 through filterVisibility's textureGrad, since this sits in non-uniform control flow.
float blendVisibility(LayerHit h) {
  if (!h.inMap) return 1.0;
  ivec2 c = centerTexel(h.lookup);
  return kFilter == kFilterNone && !kTechnique
             ? (texelFetch(mapDepth, ivec3(c, h.lookup.layer.index), 0).r >= refAt(h.lookup, c) ? 1.0 : 0.0)
             : filterVisibility(h.lookup);
}

float cascadeFar(int k) { return P.cascadeFar[k / 4][k % 4]; }

// Cascades (directional only): the pixel's view depth picks the first cascade whose far split
// is not nearer; beyond the last split, the last cascade. In the blend band at a cascade's far
// end, blendT goes 0 -> 1 towards the next cascade.
struct CascadePick {
  int cascade;
  float blendT;
};
CascadePick pickCascade(vec3 p) {
  CascadePick c = CascadePick(0, 0.0);
  if (kCascaded) {
    int cascadeCount = int(PLoops.cascadeView.w);  // a loop bound: not P's (ParamsLoops in resolve_abi.h)
    float viewDepth = dot(p - P.cameraOrigin.xyz, P.cascadeView.xyz) + P.cascadeInfo.z;  // fit camera depth
    for (int k = 0; k + 1 < cascadeCount; ++k)
      if (viewDepth > cascadeFar(k)) c.cascade = k + 1;
    if (kBlend && c.cascade + 1 < cascadeCount) {
      float farSplit = cascadeFar(c.cascade);
      float nearSplit = c.cascade == 0 ? P.cascadeInfo.y : cascadeFar(c.cascade - 1);
      float band = P.cascadeInfo.x * (farSplit - nearSplit);
      c.blendT = band > 0.0 ? clamp((viewDepth - (farSplit - band)) / band, 0.0, 1.0) : 0.0;
    }
  }
  return c;
}

int cubeFace(vec3 v) {
  vec3 a = abs(v);
  if (a.x >= a.y && a.x >= a.z) return v.x > 0.0 ? 0 : 1;
  if (a.y >= a.z) return v.y > 0.0 ? 2 : 3;
  return v.z > 0.0 ? 4 : 5;
}

// The pixel's visible surface, from the visibility buffer (kSurface: from the surface image, the
// point or its map coordinates alone; hit then also says that the light reaches it).
Surface visibleSurface(ivec2 px) {
  Surface s;
  if (kSurface) {
    vec4 surface = texelFetch(surfaceMap, px, 0);
    float reach = surface.w;  // surfaceTexel's
    s.hit = reach > 0.0;
    s.covered = reach != 0.0;
    s.uvz = surface.xyz;
    s.inMap = abs(reach) > 1.5;
    s.dir = vec3(0.0, 0.0, 1.0);  // unread, as t
    s.t = 0.0;
    s.p = kProjectedSurface ? vec3(0.0) : surface.xyz;
    s.plane = vec4(0.0);  // unread: nothing the lookup computes without a normal reads them
    s.normal = vec3(0.0, 0.0, 1.0);
    s.e1 = vec3(1.0, 0.0, 0.0);
    return s;
  }
  uint id = texelFetch(cameraIds, px, 0).x;  // global triangle + 1, 0: no hit
  s.hit = id != 0u;
  s.uvz = vec3(0.0);
  s.inMap = false;
  s.covered = s.hit;
  s.plane = texelFetch(trianglePlanes, int(id));
  vec2 pixelCenter = vec2(px) + 0.5;
  s.dir = rayThrough(pixelCenter);
  s.t = planeT(s.dir, s.plane, pixelCenter);
  s.p = rayPoint(s.dir, s.t, pixelCenter);
  s.normal = s.plane.xyz;
  if (dot(s.normal, s.dir) > 0.0) s.normal = -s.normal;  // face the camera, like the reference's N
  // A unit tangent (Duff et al. 2017's branchless basis), for the receiver plane's slope.
  float sgn = s.normal.z >= 0.0 ? 1.0 : -1.0;
  float ta = -1.0 / (sgn + s.normal.z);
  s.e1 = vec3(1.0 + sgn * s.normal.x * s.normal.x * ta, sgn * s.normal.x * s.normal.y * ta, -sgn * s.normal.x);
  return s;
}

// The light's channels of a surface, as outA and outB hold them.
struct LightChannels {
  vec4 a;  // vis, receiver_depth, map_depth, m
  vec4 b;  // bias_depth, bias_world, occluder (id), 2 * cascade + in_map
  vec4 c;  // filterable maps: moment mean, variance, bound (0 outside the map)
  bool unreached;  // the light cannot reach the visible side (facing away, outside a spot's cone)
  vec3 uvz;        // the visible point's map coordinates, and whether they lie in the map, without
  bool inMap;      // the normal offset: what a surface with kProjectedSurface holds
};

LightChannels shadeLight(Surface s) {
  vec3 p = s.p, normal = s.normal, dir = s.dir;
  vec3 lightPos = P.lightPosType.xyz;
  CascadePick pick = pickCascade(p);
  LayerHit h;
  if (kSurface && kProjectedSurface) h = surfaceHit(pick.cascade, s);
  else h = lookUp(kLightType == kLightPoint ? cubeFace(p - lightPos) : pick.cascade, s);
  Lookup L = h.lookup;
  Layer layer = L.layer;
  vec4 tP = h.tP;
  float depthP = tP.z / tP.w;

  // hw2x2 with texture() in uniform control flow rather than textureGrad inside the branch below:
  // lavapipe takes explicit gradients per pixel (about 6 ms more at 1080p). The implicit LOD
  // selects nothing: the map has one level, the sampler clamps the LOD to 0 (maxLod) and its min
  // and mag filters are the same.
  float hwVis = kFilter == kFilterHw2x2 ? texture(mapShadow, vec4(L.st / layer.size, float(layer.index), L.ref)) : 1.0;

  float vis = 1.0;  // policy: points outside the map are lit
  float mapDepthCenter = 0.0, occluder = 0.0;
  vec4 momentEvidence = vec4(0.0);
  if (h.inMap) {
    ivec2 c = centerTexel(L);
    mapDepthCenter = texelFetch(mapDepth, ivec3(c, layer.index), 0).r;
    // filter none is the center texel's comparison: no second fetch.
    if (kMomentFilter) {
      MomentLookup ml = momentLookup(L);
      vis = kTechnique ? filterVisibility(L) : ml.vis;  // a technique with a moments line: its own vis
      momentEvidence = vec4(ml.mean, ml.variance, ml.bound, 0.0);
    } else {
      vis = kTechnique                ? filterVisibility(L)
            : kFilter == kFilterNone  ? (mapDepthCenter >= refAt(L, c) ? 1.0 : 0.0)
            : kFilter == kFilterHw2x2 ? hwVis
                                      : filterVisibility(L);
    }
    occluder = float(texelFetch(mapIds, ivec3(c, layer.index), 0).x);  // the readback maps it to ids
  }
  bool outsideCone = kLightType == kLightSpot && dot(normalize(p - lightPos), P.lightDirCos.xyz) < P.lightDirCos.w;
  // Facing rule (the reference's): the side the camera sees is unlit when the light is behind
  // it. A shadow map has no answer there (the surface against itself); N.L shading gives 0.
  vec3 toLight = towardsLight(p);
  bool facesAway = !(dot(normal, toLight) > 0.0);

  // Rasterizer depth bias the map texel carries when the receiver is its own caster:
  // constant * r + slope * maxDepthSlope, clamped (Vulkan's formula; maxDepthSlope per texel).
  vec2 slope = h.planeSlope;
  float r = depthResolution(depthP);
  float rasterBias = P.depthBias.x * r + P.depthBias.y * max(abs(slope.x), abs(slope.y));
  if (P.depthBias.z > 0.0) rasterBias = min(rasterBias, P.depthBias.z);
  if (P.depthBias.z < 0.0) rasterBias = max(rasterBias, P.depthBias.z);
  // Adaptive: the bias the centre texel's comparison applied (negative where the tangent plane lies
  // beyond p at the texel centre).
  float biasDepth =
      kAdaptive ? rasterBias + depthP - refAt(L, centerTexel(L)) : P.bias.x + rasterBias + (depthP - h.uvz.z);
  vec4 tL = projectStep(layer, tP, toLight * h.texelWorld);
  float depthStep = abs(depthP - tL.z / tL.w);
  float worldPerDepth = depthStep > 0.0 ? h.texelWorld / depthStep : 0.0;

  // Lloyd's m: the Jacobian d(texel)/d(pixel), exact on the plane. The point is
  // p(x, y) = origin + d t with t = plane.w / dot(n, d) and d = rayX x + rayY y + rayC, so
  // d(project(p))/dx = t (dirMap(rayX) - dot(n, rayX) / dot(n, d) dirMap(d)), and the texel
  // coordinates (u, v) = size (X, Y) / W follow by the quotient rule. Few divisions: each
  // costs as much as several multiplies.
  vec3 nTri = s.plane.xyz;
  float invNd = 1.0 / dot(nTri, dir);
  vec4 dMap = dirMap(layer, dir);
  vec4 gx = dirMap(layer, P.rayX.xyz) - (dot(nTri, P.rayX.xyz) * invNd) * dMap;
  vec4 gy = dirMap(layer, P.rayY.xyz) - (dot(nTri, P.rayY.xyz) * invNd) * dMap;
  // Orthographic: p(x, y) = origin(x, y) + d t(x, y) moves by the same gx, gy per pixel without
  // the factor t (the rays do not spread): size / W.
  float scale = orthoCamera() ? layer.size / tP.w : layer.size * s.plane.w * invNd / tP.w;  // size t / W
  vec2 uvP = tP.xy / tP.w;
  vec2 jx = (kAffine ? gx.xy : gx.xy - uvP * gx.w) * scale, jy = (kAffine ? gy.xy : gy.xy - uvP * gy.w) * scale;
  float sumSq = dot(jx, jx) + dot(jy, jy);
  float detJ = abs(jx.x * jy.y - jy.x * jx.y);
  // The singular values of J: sMax, and sMin = detJ / sMax; m = 1 / sMin.
  float sMax = sqrt(0.5 * (sumSq + sqrt(max(sumSq * sumSq - 4.0 * detJ * detJ, 0.0))));
  // Capped where J is singular to float precision (sMin = detJ / sMax below kFootprintSingularRatio
  // sMax: a plane edge-on to the light, within about 0.0006 degrees) or m would pass the cap.
  float m = detJ > max(kFootprintSingularRatio * sMax, 1.0 / kFootprintCap) * sMax ? min(sMax / detJ, kFootprintCap)
                                                                                 : kFootprintCap;

  // The blend band: the same lookup in the next cascade.
  if (kBlend && pick.blendT > 0.0) vis = mix(vis, blendVisibility(lookUp(pick.cascade + 1, s)), pick.blendT);
  // kSurface: the surface image's hit says it (surfaceTexel); the normal is not there.
  if (!kSurface && (outsideCone || facesAway)) vis = 0.0;

  LightChannels o;
  o.unreached = outsideCone || facesAway;
  o.a = vec4(vis, h.uvz.z, mapDepthCenter, m);
  o.b = vec4(biasDepth, biasDepth * worldPerDepth, occluder, float(2 * pick.cascade + (h.inMap ? 1 : 0)));
  o.c = momentEvidence;
  // The point's own coordinates: with the normal offset, tP's, as lookUp derives tQ's.
  o.uvz = kNormalOffset ? tP.xyz / tP.w : h.uvz;
  o.inMap = kNormalOffset ? inMapAt(tP, o.uvz) : h.inMap;
  return o;
}

// The group's surface at a pixel, as the planes pass and the full resolve write it (kSurface's
// image). Its reach: 1 where a triangle covers the pixel and the light reaches it, -1 where one
// covers it and the light does not, 0 where none does. kProjectedSurface: (u, v, depth, reach),
// reach doubled where (u, v) lie in the map (0 where no triangle covers it); else (the visible
// point, reach).
vec4 surfaceTexel(Surface s, LightChannels light) {
  if (!s.hit) return vec4(0.0);
  float reach = light.unreached ? -1.0 : 1.0;
  return kProjectedSurface ? vec4(light.uvz, light.inMap ? 2.0 * reach : reach) : vec4(s.p, reach);
}

// Each projector's channels of a surface into outPlanes (pixel `pixel` of planes of `planeSize`).
// Pixels without a hit get zeros. Every pixel stores each channel exactly once: on lavapipe an
// early-out branch does not save work (both sides run masked), a second set of stores would.
void shadeProjectors(Surface s, uint pixel, uint planeSize) {
  vec3 p = s.p, normal = s.normal;
  for (int j = 0; j < kProjectorCount; ++j) {
    uint base = uint(kProjectorChannels) * uint(j);
    Layer layer = layerAt(P.sizes.y + j);
    vec4 t = layer.texFromWorld * vec4(p, 1.0);  // projectors are perspective
    vec3 puv = t.xyz / t.w;
    bool insideUv = all(greaterThanEqual(puv.xy, vec2(0.0))) && all(lessThanEqual(puv.xy, vec2(1.0)));
    bool reverse = t.w < 0.0 && insideUv;
    bool frontInFrustum = t.w > 0.0 && insideUv && puv.z >= 0.0 && puv.z <= 1.0;
    // Without the guard, points behind the projector are projected too; its depth map says
    // nothing about them (their depth lies outside [0, 1]), so nothing occludes them.
    // Facing, as for lights: a surface whose hidden side faces the projector is not covered.
    vec3 projectorPos = P.projectorPos[j].xyz;
    bool facing = dot(normal, projectorPos - p) > 0.0;
    bool covered = (frontInFrustum || (P.sizes2.w == 0 && reverse)) && facing;
    if (covered && frontInFrustum) covered = tap(layer, ivec2(floor(puv.xy * layer.size)), puv.z - P.bias.x) > 0.5;
    vec3 color = vec3(0.0);
    if (covered) {
      ivec4 info = P.projector[j];
      int x = clamp(int(floor(puv.x * float(info.y))), 0, info.y - 1);
      int y = clamp(int(floor(puv.y * float(info.z))), 0, info.z - 1);
      uint o = uint(info.x) + 3u * uint(y * info.y + x);
      color = vec3(projectorTexels[o], projectorTexels[o + 1u], projectorTexels[o + 2u]);
    }
    outPlanes[base * planeSize + pixel] = s.hit && covered ? 1.0 : 0.0;
    outPlanes[(base + 1u) * planeSize + pixel] = s.hit ? color.r : 0.0;
    outPlanes[(base + 2u) * planeSize + pixel] = s.hit ? color.g : 0.0;
    outPlanes[(base + 3u) * planeSize + pixel] = s.hit ? color.b : 0.0;
    outPlanes[(base + 4u) * planeSize + pixel] = s.hit && reverse ? 1.0 : 0.0;
  }
}

// The lookup pass's byte: the visibility as UNORM, with the extremes kept exact (255 only where
// the visibility, clamped to [0, 1], is 1; 0 only where it is 0, NaN included) and the lit
// decision kept exact (bytes 128..255 exactly where vis >= 0.5), whatever way the unit rounds.
// Every other pixel is fractional: evidence on demand resolves exactly those again for the
// float (raster/METHODS.md, "Evidence on demand").
float lookupByte(float vis) {
  float v = vis >= 1.0 ? 1.0 : (vis > 0.0 ? vis : 0.0);
  if (v > 0.0 && v < 1.0) v = v >= 0.5 ? clamp(v, 128.0 / 255.0, 254.0 / 255.0) : clamp(v, 1.0 / 255.0, 127.0 / 255.0);
  return v;
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);  // the viewport is the image: every pixel, once
  if (kCompact) {
    uint k = min(uint(px.y) * pc.compactWidth + uint(px.x), pc.count - 1u);  // the tail repeats the last
    uint pixel = evidencePixels[pc.first + k];  // x | y << 16
    px = ivec2(int(pixel & 0xffffu), int(pixel >> 16));
  }
  gPixel = px;
  Surface s = visibleSurface(px);
  LightChannels light = shadeLight(s);  // without a light (kLightNone) the readback ignores it
  if (kLookupOnly) {
    // Compact: the occluder's evidence of the listed pixels (EvidenceRequest::occluder), the full
    // resolve's vis, occluder and 2 * cascade + in_map (outA.x, outB.z, outB.w) into RGBA32F; the
    // depth, bias and m arithmetic is dead code, as in the lookup.
    if (kCompact) outA = s.covered ? vec4(s.hit ? light.a.x : 0.0, light.b.z, light.b.w, 0.0) : vec4(0.0);
    else outA = vec4(lookupByte(s.hit ? light.a.x : 0.0));  // the R8 attachment keeps x
    return;
  }
  if (kPlanesOnly) {
    outA = s.hit ? vec4(light.a.w, light.b.w, 0.0, 0.0) : vec4(0.0);
    outB = surfaceTexel(s, light);
    return;
  }
  outA = s.hit ? light.a : vec4(0.0);
  outB = s.hit ? light.b : vec4(0.0);
  if (kMomentFilter) outC = s.hit ? light.c : vec4(0.0);
  if (kCompact) return;  // no projectors (their planes are every pixel's)
  if (kMomentFilter) outD = surfaceTexel(s, light);
  else outC = surfaceTexel(s, light);
  shadeProjectors(s, uint(px.y * P.sizes2.x + px.x), uint(P.sizes2.x * P.sizes2.y));
}
