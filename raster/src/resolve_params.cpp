// The GPU-free steps of Rasterizer::render: fit, parameter packing, specialization.
#include "shadowlab/raster/resolve_params.h"

#include <algorithm>
#include <cmath>

#include "light_space.h"
#include "shadowlab/scenes/technique.h"

namespace shadowlab::raster {

namespace {
// An orthographic camera's point at image position (x, y) (pixels) and NDC depth zNdc (NaN: the
// plane through the camera position, view z = 0), through the inverse of the float matrix that
// rasterizes the visibility buffer (w = 1 for every point).
glm::dvec3 orthoRayOrigin(const Camera& camera, double x, double y, double zNdc = std::nan("")) {
  const glm::mat4 view = camera.viewFromWorld(), proj = camera.clipFromView();
  const glm::dmat4 inv = glm::inverse(glm::dmat4(proj * view));
  if (std::isnan(zNdc)) zNdc = double(proj[3][2]);  // z of view z = 0
  return glm::dvec3(inv * glm::dvec4(2.0 * x / camera.width - 1.0, 2.0 * y / camera.height - 1.0, zNdc, 1.0));
}
}  // namespace

glm::dvec3 cameraRaysOrigin(const Camera& camera) {
  // Rounded to float as Params::cameraOrigin holds it, so the planes and the shader's rays agree.
  return camera.orthographic() ? glm::dvec3(glm::vec3(orthoRayOrigin(camera, 0, 0))) : glm::dvec3(camera.position);
}

static_assert(abi::kLightDirectional == int(LightType::Directional) && abi::kLightSpot == int(LightType::Spot) &&
                  abi::kLightPoint == int(LightType::Point),
              "the shader's light codes are kinds.h's rows");
static_assert(abi::kFilterNone == int(Filter::None) && abi::kFilterPoisson == int(Filter::Poisson) &&
                  abi::kFilterMsm == int(Filter::Msm),
              "the shader's filter codes are kinds.h's rows");

FrameLayers fitFrameLayers(const Scene& scene, const Light* light, const Method& method, const Camera& fitCamera,
                           const std::vector<glm::vec3>* visiblePoints) {
  FrameLayers out;
  if (light) {
    LightSpace lightSpace = fitLight(scene, *light, method, fitCamera, visiblePoints);
    out.layers = std::move(lightSpace.layers);
    out.depthClamp = lightSpace.depthClamp;
    out.cascadeSplitsView = std::move(lightSpace.cascadeSplitsView);
  }
  out.lightLayers = int(out.layers.size());
  for (const Projector& p : scene.projectors) out.layers.push_back(projectorLayer(p, method.mapSize));
  return out;
}

bool fitReadsVisiblePoints(const Light* light, const Method& method) {
  return light && light->type == LightType::Directional && method.fit == Fit::Sdsm;
}

// Mitchell's best candidate with a fixed seed: any prefix of `taps` points is itself well
// spread, so filter.taps can be swept without a new table.
const std::vector<glm::vec2>& poissonDisc() {
  static const std::vector<glm::vec2> disc = [] {
    std::vector<glm::vec2> points;
    uint32_t state = 12345u;
    auto next = [&state] {
      state = state * 1664525u + 1013904223u;
      return float(state >> 8) / float(1u << 24);
    };
    while (points.size() < size_t(abi::kMaxTaps)) {
      glm::vec2 best(0);
      float bestDistance = -1;
      int candidates = int(points.size()) * 4 + 1;
      for (int c = 0; c < candidates; ++c) {
        glm::vec2 p;
        do p = glm::vec2(next(), next()) * 2.0f - 1.0f;
        while (glm::dot(p, p) > 1.0f);
        float d = 1e9f;
        for (auto& q : points) d = std::min(d, glm::dot(p - q, p - q));
        if (d > bestDistance) bestDistance = d, best = p;
      }
      points.push_back(best);
    }
    return points;
  }();
  return disc;
}

float depthResolution(DepthFormat format) {
  switch (format) {
    case DepthFormat::D16: return std::ldexp(1.0f, -16);
    case DepthFormat::D24: return std::ldexp(1.0f, -24);
    case DepthFormat::D32F: return 0.0f;
  }
  return 0.0f;
}

glm::vec4 lightSizeInMap(const Light& light, const MapLayer& layer, int mapSize) {
  const glm::mat4& m = layer.texFromWorld;  // glm: m[column][row]
  auto row = [&](int i) { return glm::dvec3(m[0][i], m[1][i], m[2][i]); };
  const bool affine = m[0][3] == 0.0f && m[1][3] == 0.0f && m[2][3] == 0.0f && m[3][3] == 1.0f;
  const double size = double(mapSize);
  if (affine) {
    // Orthographic: a disc of angular diameter theta at infinity; a blocker dz (world, along the
    // light) in front of the receiver casts a penumbra of radius dz tan(theta / 2). The map's depth
    // is linear, dz = (d_r - d_b) / |depth row| (world per unit of depth), and one world unit
    // across is size * |u row| texels (|v row| down).
    if (light.type != LightType::Directional || !(light.angularDiameterDeg > 0.0f)) return glm::vec4(0.0f);
    const double halfTan = std::tan(0.5 * double(light.angularDiameterDeg) * 3.14159265358979323846 / 180.0);
    const double worldPerDepth = 1.0 / glm::length(row(2));
    return glm::vec4(float(halfTan * worldPerDepth * size * glm::length(row(0))),
                     float(halfTan * worldPerDepth * size * glm::length(row(1))), 0.0f, 0.0f);
  }
  // Perspective (spot, cube face; warped directional fits are refused with the soft filters): a
  // sphere of radius R at the map's eye. A blocker at view distance z_b casts, on a receiver at z_r,
  // a penumbra of radius R (z_r - z_b) / z_b (world), which the map shows at z_r as
  // R (z_r - z_b) / (z_b z_r) times the texels per unit of x / w: size |u row's part across w|.
  // The depth row is A * (w row) plus a constant, depth = A + B / w, so z_lin = w = B / (d - A).
  if (light.type == LightType::Directional || !(light.radius > 0.0f)) return glm::vec4(0.0f);
  const glm::dvec3 w = row(3);
  const double ww = glm::dot(w, w);
  if (!(ww > 0.0)) return glm::vec4(0.0f);
  const double a = glm::dot(row(2), w) / ww;
  const double b = double(m[3][2]) - a * double(m[3][3]);
  auto across = [&](int i) { return glm::length(row(i) - w * (glm::dot(row(i), w) / ww)); };
  const double r = double(light.radius) * size;
  return glm::vec4(float(r * across(0)), float(r * across(1)), float(a), float(b));
}

uint32_t lightTypeCode(const Light* light) { return light ? uint32_t(light->type) : uint32_t(abi::kLightNone); }

abi::Params packResolveParams(const Scene& scene, const Light* light, const Method& method, const Camera& fitCamera,
                              const FrameLayers& frameLayers, const std::vector<ProjectorTexels>& projectorTexels) {
  const Camera& camera = scene.camera;
  const std::vector<MapLayer>& layers = frameLayers.layers;
  const int width = camera.width, height = camera.height;
  const int projectorCount = int(scene.projectors.size());
  abi::Params prm{};
  for (size_t i = 0; i < layers.size(); ++i) {
    prm.texFromWorld[i] = layers[i].texFromWorld;
    prm.layerInfo[i] = glm::vec4(layers[i].texelWorldPerW, 0, 0, 0);
  }
  if (light) {
    prm.lightPosType = glm::vec4(light->position, float(lightTypeCode(light)));
    prm.lightDirCos = glm::vec4(glm::normalize(light->direction), std::cos(glm::radians(0.5f * light->coneDeg)));
  } else {
    prm.lightPosType = glm::vec4(0, 0, 0, -1.0f);
  }
  if (camera.orthographic()) {
    // Parallel rays (rayC.w = 1): dir = rayC, from origin(x, y) = cameraOrigin + rayX x + rayY y on
    // the plane through the camera position, all from the inverse of the very matrix that
    // rasterized the visibility buffer (w = 1 everywhere).
    const glm::dvec3 o = cameraRaysOrigin(camera);
    prm.cameraOrigin = glm::vec4(glm::vec3(o), 1);
    prm.rayC = glm::vec4(glm::vec3(orthoRayOrigin(camera, 0, 0, 1.0) - orthoRayOrigin(camera, 0, 0, 0.0)), 1);
    prm.rayX = glm::vec4(glm::vec3(orthoRayOrigin(camera, 1, 0) - o), 0);
    prm.rayY = glm::vec4(glm::vec3(orthoRayOrigin(camera, 0, 1) - o), 0);
  } else {
    // Rays through image points, from the inverse of the very matrix that rasterized the
    // visibility buffer: dir(x, y) = rayX x + rayY y + rayC (affine: w of an unprojected
    // far-plane point does not depend on x, y).
    glm::mat4 cameraClip = camera.clipFromView() * camera.viewFromWorld();
    glm::dmat4 inv = glm::inverse(glm::dmat4(cameraClip));
    glm::dvec3 origin(camera.position);
    auto dirAt = [&](double x, double y) {
      glm::dvec4 f = inv * glm::dvec4(2.0 * x / width - 1.0, 2.0 * y / height - 1.0, 1.0, 1.0);
      return glm::dvec3(f) / f.w - origin;
    };
    glm::dvec3 c = dirAt(0, 0);
    prm.cameraOrigin = glm::vec4(camera.position, 1);
    prm.rayC = glm::vec4(glm::vec3(c), 0);
    prm.rayX = glm::vec4(glm::vec3(dirAt(1, 0) - c), 0);
    prm.rayY = glm::vec4(glm::vec3(dirAt(0, 1) - c), 0);
  }
  prm.bias =
      glm::vec4(method.biasCompare, method.biasNormal, method.biasReceiverPlane ? 1.0f : 0.0f, method.filterRadius);
  prm.adaptive = glm::vec4(method.biasAdaptiveEpsilon, 0.0f, 0.0f, 0.0f);
  if (frameLayers.lightLayers > 0 && frameLayers.layers[0].lightDepth)
    prm.lightDepth = frameLayers.layers[0].depthFromWorld;
  prm.depthBias = glm::vec4(method.biasConstant, method.biasSlope, method.biasClamp, depthResolution(method.mapFormat));
  prm.sizes = glm::ivec4(method.mapSize, frameLayers.lightLayers, projectorCount, method.filterSize);
  prm.sizes2 = glm::ivec4(width, height, method.filterTaps, method.projectorReverseGuard ? 1 : 0);
  for (int j = 0; j < projectorCount && j < int(projectorTexels.size()); ++j) {
    const ProjectorTexels& pt = projectorTexels[size_t(j)];
    prm.projector[j] = glm::ivec4(pt.firstTexel, pt.width, pt.height, frameLayers.lightLayers + j);
    prm.projectorPos[j] = glm::vec4(scene.projectors[size_t(j)].position, 1);
  }
  if (!frameLayers.cascadeSplitsView.empty()) {
    const std::vector<float>& c = frameLayers.cascadeSplitsView;
    int count = int(c.size()) - 1;
    // The splits are view depths of the fit camera: the shader measures a pixel's depth from the
    // evaluation camera's origin, so z carries the shift between the two origins along the fit
    // camera's forward axis (0 when they are the same camera).
    glm::vec3 forward = glm::normalize(fitCamera.lookAt - fitCamera.position);
    prm.cascadeView = glm::vec4(forward, float(count));
    for (int i = 0; i < count; ++i) prm.cascadeFar[i / 4][i % 4] = c[size_t(i) + 1];
    float originShiftView = glm::dot(camera.position - fitCamera.position, forward);
    prm.cascadeInfo = glm::vec4(method.cascadeBlend, c[0], originShiftView, 0);
  }
  // Filterable maps: EVSM's exponents clamped to what the 32F moments hold (kEvsmMaxExponent).
  prm.moments = glm::vec4(method.vsmMinVariance, method.vsmBleedReduction,
                          std::min(method.evsmExponentPos, abi::kEvsmMaxExponent),
                          std::min(method.evsmExponentNeg, abi::kEvsmMaxExponent));
  prm.moments2 = glm::vec4(method.msmMomentBias, float(method.filterBlur), 0, 0);
  prm.softTaps = glm::ivec4(method.pcssBlockerTaps, method.pcssFilterTaps, method.dpcfTaps,
                            (method.filter == Filter::Dpcf ? method.dpcfRotate : method.pcssRotate) ? 1 : 0);
  prm.softInfo = glm::vec4(method.pcssMinFilter, method.pcssMaxPenumbra, method.dpcfMaxPenumbra, 0.0f);
  if (light)
    for (int i = 0; i < frameLayers.lightLayers && i < abi::kMaxLightLayers; ++i)
      prm.lightSize[i] = lightSizeInMap(*light, layers[size_t(i)], method.mapSize);
  const std::vector<glm::vec2>& poisson = poissonDisc();
  for (int i = 0; i < abi::kMaxTaps; ++i) prm.poisson[i] = glm::vec4(poisson[size_t(i)], 0, 0);
  return prm;
}

ResolveSpecialization resolveSpecialization(const Scene& scene, const Light* light, const Method& method,
                                            const FrameLayers& frameLayers) {
  const bool cascaded = !frameLayers.cascadeSplitsView.empty();
  bool affine = frameLayers.lightLayers > 0;
  for (int i = 0; i < frameLayers.lightLayers; ++i) {
    const glm::mat4& t = frameLayers.layers[size_t(i)].texFromWorld;
    affine = affine && t[0][3] == 0.0f && t[1][3] == 0.0f && t[2][3] == 0.0f && t[3][3] == 1.0f;
  }
  ResolveSpecialization spec{};
  spec[abi::kSpecFilter] = uint32_t(method.filter);
  spec[abi::kSpecProjectorCount] = uint32_t(scene.projectors.size());
  spec[abi::kSpecCascaded] = cascaded ? 1u : 0u;
  spec[abi::kSpecBlend] = cascaded && method.cascadeBlend > 0.0f ? 1u : 0u;
  spec[abi::kSpecFloatDepth] = depthResolution(method.mapFormat) > 0.0f ? 0u : 1u;
  spec[abi::kSpecLightType] = lightTypeCode(light);
  spec[abi::kSpecAffine] = affine ? 1u : 0u;
  spec[abi::kSpecOrthoCamera] = scene.camera.orthographic() ? 1u : 0u;
  spec[abi::kSpecAdaptive] = method.biasAdaptive ? 1u : 0u;
  // One light depth row for every light layer: only fit=tsm's single layer has one.
  spec[abi::kSpecLightDepth] = frameLayers.lightLayers > 0 && frameLayers.layers[0].lightDepth ? 1u : 0u;
  // Uniform switches as specialization constants: lavapipe runs both sides of a branch on a
  // uniform-buffer value, so their code costs every pixel even when off.
  spec[abi::kSpecReceiverPlane] = method.biasReceiverPlane ? 1u : 0u;
  spec[abi::kSpecTechniqueNormal] =
      light && !method.technique.empty() && loadTechniqueFile(method.technique).readsPlaneSlope ? 1u : 0u;
  spec[abi::kSpecNormalOffset] = method.biasNormal != 0.0f ? 1u : 0u;
  spec[abi::kSpecPcfSize] = method.filter == Filter::Pcf ? uint32_t(method.filterSize) : 0u;
  return spec;
}

}  // namespace shadowlab::raster
