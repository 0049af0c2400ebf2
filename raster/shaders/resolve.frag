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

// Specialized per filter so lavapipe compiles straight-line code for the cheap filters.
layout(constant_id = 0) const uint kFilter = 0u;  // 0 none, 1 hw2x2, 2 bilinear4, 3 pcf, 4 poisson
// The scene's projector count: lavapipe runs every branch of a shader masked, so an empty
// projector loop still costs unless it is compiled out.
layout(constant_id = 1) const int kProjectorCount = 0;
// Cascades (directional light, fit=cascades), a blend band, a float depth format: off, their
// code is compiled out (lavapipe would run it masked for every pixel).
layout(constant_id = 2) const bool kCascaded = false;
layout(constant_id = 3) const bool kBlend = false;
layout(constant_id = 4) const bool kFloatDepth = false;
// The light's type (0 directional, 1 spot, 2 point, 3 none): the other types' code compiled out.
layout(constant_id = 5) const int kLightType = 0;
// Every light layer is affine (orthographic: texFromWorld's last row is (0, 0, 0, 1)), so w = 1
// and the divisions by it fold away; the results are the same bits.
layout(constant_id = 6) const bool kAffine = false;

const int kMaxLayers = 16;  // 8 light layers (cascades; a cube: 6) + 8 projectors
const int kMaxProjectors = 8;
const int kMaxTaps = 64;

layout(std140, set = 0, binding = 3) uniform Params {
  mat4 texFromWorld[kMaxLayers];  // world -> (u*w, v*w, depth*w, w), u,v in [0,1], v = 0 top
  vec4 layerInfo[kMaxLayers];     // x: world size of one texel per unit of w
  vec4 lightPosType;              // xyz position (w: the type, which the shader takes from kLightType)
  vec4 lightDirCos;               // xyz direction of travel, w: cos(cone / 2)
  vec4 cameraOrigin;              // xyz
  vec4 rayX;                      // unnormalized ray direction through image point (x, y):
  vec4 rayY;                      //   rayX * x + rayY * y + rayC (x, y in pixels)
  vec4 rayC;
  vec4 bias;        // x compare (depth), y normal (texels), z receiver plane (0/1), w poisson radius (texels)
  vec4 depthBias;   // x constant factor, y slope factor, z clamp, w r of the format (0: float format)
  ivec4 sizes;      // x map size, y light layers, z projector count, w pcf size
  ivec4 sizes2;     // x width, y height, z poisson taps, w reverse guard (0/1)
  ivec4 projector[kMaxProjectors];  // x first texel in projectorTexels, y width, z height
  vec4 poisson[kMaxTaps];           // xy: unit-disc offsets
  vec4 projectorPos[kMaxProjectors];  // xyz: world position
  vec4 cascadeView;   // xyz fit camera forward (unit), w cascade count (0: not cascaded)
  vec4 cascadeFar[2]; // C_1..C_8: far view depth of cascade 0..7, world units
  vec4 cascadeInfo;   // x blend band (fraction of a cascade's depth range), y C_0, z fit depth - eval depth
} P;

layout(set = 0, binding = 4) uniform sampler2DArray mapDepth;         // NEAREST, raw depth
layout(set = 0, binding = 5) uniform sampler2DArrayShadow mapShadow;  // LINEAR, compare LESS_OR_EQUAL
layout(set = 0, binding = 6) uniform usampler2DArray mapIds;
layout(set = 0, binding = 7) uniform usampler2D cameraIds;

// Per triangle (at its global index + 1, as in the id attachments; texel 0 a placeholder), its
// plane relative to the camera origin o: (n, dot(n, v0 - o)), n the unit normal
// (v1 - v0) x (v2 - v0), computed in double on the CPU. A texel buffer: on lavapipe a
// storage-buffer load at a per-pixel address is a bounds-checked loop over the SIMD lanes, a
// texel fetch one gather; and one fetch per pixel, since each costs about as much as the rest of
// the arithmetic.
layout(set = 0, binding = 8) uniform samplerBuffer trianglePlanes;
layout(std430, set = 0, binding = 9) readonly buffer ProjectorTexels { float projectorTexels[]; };
layout(std430, set = 0, binding = 10) writeonly buffer OutPlanes { float outPlanes[]; };

// The rasterizer splits these into the frame's channels (rasterizer.cpp, readback).
layout(location = 0) out vec4 outA;  // vis, receiver_depth, map_depth, m
layout(location = 1) out vec4 outB;  // bias_depth, bias_world, occluder (id), 2 * cascade + in_map
const uint kProjectorChannels = 5u;

uint gPixel;
uint gPlane;
bool gHit;
// Pixels without a hit get zeros. Every pixel stores each channel exactly once: on lavapipe an
// early-out branch does not save work (both sides run masked), a second set of stores would.
void put(uint channel, float value) { outPlanes[channel * gPlane + gPixel] = gHit ? value : 0.0; }

vec3 rayThrough(vec2 pixel) { return P.rayX.xyz * pixel.x + P.rayY.xyz * pixel.y + P.rayC.xyz; }
// Where the camera ray through an image point meets a plane (n, dot(n, v0 - origin)).
vec3 planePoint(vec2 pixel, vec4 plane) {
  vec3 d = rayThrough(pixel);
  return P.cameraOrigin.xyz + d * (plane.w / dot(d, plane.xyz));
}

int gLayer;
mat4 gTexFromWorld;  // P.texFromWorld[gLayer], fetched once: dynamic UBO indexing is a gather on CPUs
float gSize;
// The light layer's homogeneous coordinates of a point; they move by dirMap(v) per unit of v:
// project(p + v) = project(p) + dirMap(v).
vec4 project(vec3 pWorld) {
  vec4 t = gTexFromWorld * vec4(pWorld, 1.0);
  if (kAffine) t.w = 1.0;
  return t;
}
vec4 dirMap(vec3 v) {
  vec4 t = gTexFromWorld[0] * v.x + gTexFromWorld[1] * v.y + gTexFromWorld[2] * v.z;
  if (kAffine) t.w = 0.0;
  return t;
}

// Lit (1) when the stored depth is not in front of the reference depth.
float tap(ivec2 texel, float depthRef) {
  ivec2 c = clamp(texel, ivec2(0), ivec2(int(gSize) - 1));
  return texelFetch(mapDepth, ivec3(c, gLayer), 0).r >= depthRef ? 1.0 : 0.0;
}

vec2 gSlope;   // receiver plane: d(depth)/d(texel u, v), zero when bias.receiver_plane is off
vec2 gSt;      // lookup position in texels
float gRef;    // reference depth at gSt (receiver depth - compare bias)
float refAt(ivec2 texel) { return gRef + dot(gSlope, vec2(texel) + 0.5 - gSt); }

// The 2x2 texels t, t + (1, 0), t + (0, 1), t + (1, 1) in one fetch: textureGather at their shared
// corner returns them as (w, z, x, y) (Vulkan's order), clamped at the map's edge like tap()'s.
// On lavapipe every texel fetch is a call; one gather costs about what one texelFetch does.
vec4 gather4(ivec2 t) { return textureGather(mapDepth, vec3((vec2(t) + 1.0) / gSize, float(gLayer))); }
float lit(float stored, ivec2 texel) { return stored >= refAt(texel) ? 1.0 : 0.0; }

float filterVisibility() {
  ivec2 center = ivec2(floor(gSt));
  if (kFilter == 1u) {
    // The hardware blends four comparisons; the receiver plane cannot be applied per tap.
    // (main() looks up its own layer with texture(), see hwVis; this is the blend band's lookup.)
    return textureGrad(mapShadow, vec4(gSt / gSize, float(gLayer), gRef), vec2(0.0), vec2(0.0));
  } else if (kFilter == 2u) {
    vec2 s = gSt - 0.5;
    ivec2 i0 = ivec2(floor(s));
    vec2 f = s - floor(s);
    vec4 g = gather4(i0);
    float v00 = lit(g.w, i0), v10 = lit(g.z, i0 + ivec2(1, 0));
    float v01 = lit(g.x, i0 + ivec2(0, 1)), v11 = lit(g.y, i0 + ivec2(1, 1));
    return mix(mix(v00, v10, f.x), mix(v01, v11, f.x), f.y);
  } else if (kFilter == 3u) {
    // The (2h + 1)^2 taps as 2x2 gathers; the last row and column of gathers use half their
    // texels. The sum counts whole taps, so its order does not change it.
    int h = P.sizes.w / 2;
    float sum = 0.0;
    for (int by = -h; by <= h; by += 2)
      for (int bx = -h; bx <= h; bx += 2) {
        ivec2 t = center + ivec2(bx, by);
        vec4 g = gather4(t);
        bool right = bx < h, down = by < h;
        sum += lit(g.w, t);
        sum += right ? lit(g.z, t + ivec2(1, 0)) : 0.0;
        sum += down ? lit(g.x, t + ivec2(0, 1)) : 0.0;
        sum += right && down ? lit(g.y, t + ivec2(1, 1)) : 0.0;
      }
    float n = float(2 * h + 1);
    return sum / (n * n);
  } else if (kFilter == 4u) {
    int taps = P.sizes2.z;
    float sum = 0.0;
    for (int i = 0; i < taps; ++i) {
      ivec2 t = ivec2(floor(gSt + P.poisson[i].xy * P.bias.w));
      sum += tap(t, refAt(t));
    }
    return sum / float(taps);
  }
  return tap(center, refAt(center));
}

// The receiver's plane in map space, from two tangent points one texel away: the same
// (dz/du, dz/dv) the dFdx/dFdy solve yields, without its singularity at grazing views.
// tQ = project(q); the tangent points' coordinates follow from it by linearity.
vec2 planeSlope(vec4 tQ, vec3 normal, vec3 e1, float texelWorld) {
  vec3 e2 = cross(normal, e1);
  vec4 t1 = tQ + dirMap(e1 * texelWorld), t2 = tQ + dirMap(e2 * texelWorld);
  vec3 m0 = vec3(tQ.xy / tQ.w * gSize, tQ.z / tQ.w), m1 = vec3(t1.xy / t1.w * gSize, t1.z / t1.w),
       m2 = vec3(t2.xy / t2.w * gSize, t2.z / t2.w);
  vec2 a1 = m1.xy - m0.xy, a2 = m2.xy - m0.xy;
  float det = a1.x * a2.y - a1.y * a2.x;
  return abs(det) > 1e-12 ? vec2((m1.z - m0.z) * a2.y - (m2.z - m0.z) * a1.y,
                                 (m2.z - m0.z) * a1.x - (m1.z - m0.z) * a2.x) / det
                          : vec2(0.0);
}

float cascadeFar(int k) { return P.cascadeFar[k / 4][k % 4]; }

// The filtered map visibility of point p in another layer (the next cascade of a blend band):
// the same lookup as the main one (normal offset, receiver plane, filter), policy lit outside
// the map. Leaves gLayer, gTexFromWorld, gSt, gRef, gSlope set to that layer.
float layerVisibility(int layer, vec3 p, vec3 normal, vec3 e1) {
  gLayer = layer;
  gTexFromWorld = P.texFromWorld[layer];
  float texelWorld = P.layerInfo[layer].x * abs(project(p).w);
  vec3 q = p + normal * (P.bias.y * texelWorld);
  vec4 tQ = project(q);
  vec3 uvz = tQ.xyz / tQ.w;
  gSt = uvz.xy * gSize;
  bool inMap = tQ.w > 0.0 && all(greaterThanEqual(uvz.xy, vec2(0.0))) && all(lessThanEqual(uvz.xy, vec2(1.0)));
  if (!inMap) return 1.0;
  gSlope = P.bias.z > 0.5 ? planeSlope(tQ, normal, e1, texelWorld) : vec2(0.0);
  gRef = uvz.z - P.bias.x;
  ivec2 c = clamp(ivec2(floor(gSt)), ivec2(0), ivec2(int(gSize) - 1));
  return kFilter == 0u ? (texelFetch(mapDepth, ivec3(c, gLayer), 0).r >= refAt(c) ? 1.0 : 0.0) : filterVisibility();
}

int cubeFace(vec3 v) {
  vec3 a = abs(v);
  if (a.x >= a.y && a.x >= a.z) return v.x > 0.0 ? 0 : 1;
  if (a.y >= a.z) return v.y > 0.0 ? 2 : 3;
  return v.z > 0.0 ? 4 : 5;
}

void main() {
  int width = P.sizes2.x;
  ivec2 px = ivec2(gl_FragCoord.xy);  // the viewport is the image: every pixel, once
  gPixel = uint(px.y * width + px.x);
  gPlane = uint(width * P.sizes2.y);

  uint id = texelFetch(cameraIds, px, 0).x;  // global triangle + 1, 0: no hit
  gHit = id != 0u;
  vec4 plane = texelFetch(trianglePlanes, int(id));
  vec3 nTri = plane.xyz;
  vec3 origin = P.cameraOrigin.xyz;
  vec2 pixelCenter = vec2(px) + 0.5;
  vec3 dir = rayThrough(pixelCenter);
  vec3 p = planePoint(pixelCenter, plane);
  vec3 normal = nTri;
  if (dot(normal, dir) > 0.0) normal = -normal;  // face the camera, like the reference's N
  // A unit tangent (Duff et al. 2017's branchless basis), for the receiver plane's slope.
  float sgn = normal.z >= 0.0 ? 1.0 : -1.0;
  float ta = -1.0 / (sgn + normal.z);
  vec3 e1 = vec3(1.0 + sgn * normal.x * normal.x * ta, sgn * normal.x * normal.y * ta, -sgn * normal.x);

  // ---- the light ----
  const int lightType = kLightType;
  vec3 lightPos = P.lightPosType.xyz;
  gSize = float(P.sizes.x);
  // Cascades (directional only): the pixel's view depth picks the first cascade whose far split
  // is not nearer; beyond the last split, the last cascade. In the blend band at a cascade's far
  // end, blendT goes 0 -> 1 towards the next cascade.
  int cascadeCount = kCascaded ? int(P.cascadeView.w) : 0;
  int cascade = 0;
  float blendT = 0.0;
  if (kCascaded) {
    float viewDepth = dot(p - origin, P.cascadeView.xyz) + P.cascadeInfo.z;  // fit camera depth
    for (int k = 0; k + 1 < cascadeCount; ++k)
      if (viewDepth > cascadeFar(k)) cascade = k + 1;
    if (kBlend && cascade + 1 < cascadeCount) {
      float farSplit = cascadeFar(cascade);
      float nearSplit = cascade == 0 ? P.cascadeInfo.y : cascadeFar(cascade - 1);
      float band = P.cascadeInfo.x * (farSplit - nearSplit);
      blendT = band > 0.0 ? clamp((viewDepth - (farSplit - band)) / band, 0.0, 1.0) : 0.0;
    }
  }
  gLayer = lightType == 2 ? cubeFace(p - lightPos) : cascade;
  gTexFromWorld = P.texFromWorld[gLayer];
  vec4 tP = project(p);
  float texelWorld = P.layerInfo[gLayer].x * abs(tP.w);
  vec3 q = p + normal * (P.bias.y * texelWorld);  // normal-offset lookup point
  vec4 tQ = project(q);
  bool inFront = tQ.w > 0.0;
  vec3 uvz = tQ.xyz / tQ.w;
  gSt = uvz.xy * gSize;
  bool inMap = inFront && all(greaterThanEqual(uvz.xy, vec2(0.0))) && all(lessThanEqual(uvz.xy, vec2(1.0)));
  float depthP = tP.z / tP.w;

  vec2 slope = planeSlope(tQ, normal, e1, texelWorld);
  gSlope = P.bias.z > 0.5 ? slope : vec2(0.0);
  gRef = uvz.z - P.bias.x;

  // hw2x2 with texture() in uniform control flow rather than textureGrad inside the branch below:
  // lavapipe takes explicit gradients per pixel (about 6 ms more at 1080p). The implicit LOD
  // selects nothing: the map has one level, the sampler clamps the LOD to 0 (maxLod) and its min
  // and mag filters are the same.
  float hwVis = kFilter == 1u ? texture(mapShadow, vec4(gSt / gSize, float(gLayer), gRef)) : 1.0;

  float vis = 1.0;  // policy: points outside the map are lit
  float mapDepthCenter = 0.0, occluder = 0.0;
  if (inMap) {
    ivec2 c = clamp(ivec2(floor(gSt)), ivec2(0), ivec2(int(gSize) - 1));
    mapDepthCenter = texelFetch(mapDepth, ivec3(c, gLayer), 0).r;
    // filter none is the center texel's comparison: no second fetch.
    vis = kFilter == 0u ? (mapDepthCenter >= refAt(c) ? 1.0 : 0.0) : kFilter == 1u ? hwVis : filterVisibility();
    occluder = float(texelFetch(mapIds, ivec3(c, gLayer), 0).x);  // the readback maps it to ids
  }
  bool outsideCone = lightType == 1 && dot(normalize(p - lightPos), P.lightDirCos.xyz) < P.lightDirCos.w;
  // Facing rule (the reference's): the side the camera sees is unlit when the light is behind
  // it. A shadow map has no answer there (the surface against itself); N.L shading gives 0.
  vec3 toLight = lightType == 0 ? -P.lightDirCos.xyz : normalize(lightPos - p);
  bool facesAway = !(dot(normal, toLight) > 0.0);

  // Rasterizer depth bias the map texel carries when the receiver is its own caster:
  // constant * r + slope * maxDepthSlope, clamped (Vulkan's formula; maxDepthSlope per texel).
  float r = kFloatDepth ? exp2(floor(log2(max(depthP, 1e-30))) - 23.0) : P.depthBias.w;
  float rasterBias = P.depthBias.x * r + P.depthBias.y * max(abs(slope.x), abs(slope.y));
  if (P.depthBias.z > 0.0) rasterBias = min(rasterBias, P.depthBias.z);
  if (P.depthBias.z < 0.0) rasterBias = max(rasterBias, P.depthBias.z);
  float biasDepth = P.bias.x + rasterBias + (depthP - uvz.z);
  vec4 tL = tP + dirMap(toLight * texelWorld);
  float depthStep = abs(depthP - tL.z / tL.w);
  float worldPerDepth = depthStep > 0.0 ? texelWorld / depthStep : 0.0;

  // Lloyd's m: the Jacobian d(texel)/d(pixel), exact on the plane. The point is
  // p(x, y) = origin + d t with t = plane.w / dot(n, d) and d = rayX x + rayY y + rayC, so
  // d(project(p))/dx = t (dirMap(rayX) - dot(n, rayX) / dot(n, d) dirMap(d)), and the texel
  // coordinates (u, v) = gSize (X, Y) / W follow by the quotient rule. Few divisions: each
  // costs as much as several multiplies.
  float invNd = 1.0 / dot(nTri, dir);
  vec4 dMap = dirMap(dir);
  vec4 gx = dirMap(P.rayX.xyz) - (dot(nTri, P.rayX.xyz) * invNd) * dMap;
  vec4 gy = dirMap(P.rayY.xyz) - (dot(nTri, P.rayY.xyz) * invNd) * dMap;
  float scale = gSize * plane.w * invNd / tP.w;  // gSize t / W
  vec2 uvP = tP.xy / tP.w;
  vec2 jx = (kAffine ? gx.xy : gx.xy - uvP * gx.w) * scale, jy = (kAffine ? gy.xy : gy.xy - uvP * gy.w) * scale;
  float sumSq = dot(jx, jx) + dot(jy, jy);
  float detJ = abs(jx.x * jy.y - jy.x * jx.y);
  // The singular values of J: sMax, and sMin = detJ / sMax; m = 1 / sMin.
  float sMax = sqrt(0.5 * (sumSq + sqrt(max(sumSq * sumSq - 4.0 * detJ * detJ, 0.0))));
  float m = detJ > 1e-6 * sMax ? min(sMax / detJ, 1e6) : 1e6;

  // Last, because it moves the lookup globals to the next cascade's layer.
  if (kBlend && blendT > 0.0) vis = mix(vis, layerVisibility(cascade + 1, p, normal, e1), blendT);
  if (outsideCone || facesAway) vis = 0.0;

  outA = gHit ? vec4(vis, uvz.z, mapDepthCenter, m) : vec4(0.0);
  outB = gHit ? vec4(biasDepth, biasDepth * worldPerDepth, occluder, float(2 * cascade + (inMap ? 1 : 0))) : vec4(0.0);

  // ---- projectors ----
  for (int j = 0; j < kProjectorCount; ++j) {
    uint base = kProjectorChannels * uint(j);
    gLayer = P.sizes.y + j;
    gTexFromWorld = P.texFromWorld[gLayer];
    vec4 t = gTexFromWorld * vec4(p, 1.0);  // projectors are perspective
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
    if (covered && frontInFrustum) covered = tap(ivec2(floor(puv.xy * gSize)), puv.z - P.bias.x) > 0.5;
    vec3 color = vec3(0.0);
    if (covered) {
      ivec4 info = P.projector[j];
      int x = clamp(int(floor(puv.x * float(info.y))), 0, info.y - 1);
      int y = clamp(int(floor(puv.y * float(info.z))), 0, info.z - 1);
      uint o = uint(info.x) + 3u * uint(y * info.y + x);
      color = vec3(projectorTexels[o], projectorTexels[o + 1u], projectorTexels[o + 2u]);
    }
    put(base, covered ? 1.0 : 0.0);
    put(base + 1u, color.r);
    put(base + 2u, color.g);
    put(base + 3u, color.b);
    put(base + 4u, reverse ? 1.0 : 0.0);
  }
}
