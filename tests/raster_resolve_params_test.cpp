// render()'s GPU-free steps: the fit (map layers), the resolve parameter block and the resolve
// specialization, checked on small scenes whose answers follow from the setup.
#include <gtest/gtest.h>

#include <cmath>

#include "shadowlab/raster/resolve_params.h"
#include "support/quad.h"

namespace raster_resolve_params_test {

using namespace shadowlab;
using namespace shadowlab::raster;

namespace {

// A 10 x 10 floor at y = 0 and a 2 x 2 roof at y = 1; the camera at (0, 6, 6) looks at the origin.
Scene roofScene() {
  Scene s;
  s.name = "roof";
  s.materials.push_back(Material{});
  shadowlab::testing::addQuad(s, 1, {-5, 0, 5}, {10, 0, 0}, {0, 0, -10});
  shadowlab::testing::addQuad(s, 2, {-1, 1, 1}, {2, 0, 0}, {0, 0, -2});
  s.camera.position = {0, 6, 6};
  s.camera.lookAt = {0, 0, 0};
  s.camera.width = 160;
  s.camera.height = 120;
  s.camera.vfovDeg = 50;
  Light sun;
  sun.name = "sun";
  sun.direction = {0, -1, 0};
  s.lights.push_back(sun);
  return s;
}

Light spotAt(glm::vec3 position, glm::vec3 direction, float coneDeg) {
  Light l;
  l.name = "spot";
  l.type = LightType::Spot;
  l.position = position;
  l.direction = direction;
  l.coneDeg = coneDeg;
  return l;
}

glm::vec3 uvDepth(const glm::mat4& texFromWorld, glm::vec3 p) {
  glm::vec4 t = texFromWorld * glm::vec4(p, 1.0f);
  return glm::vec3(t) / t.w;
}

}  // namespace

TEST(RasterResolveParams, SphereFitHoldsTheWholeSceneInOneAffineLayer) {
  Scene s = roofScene();
  Method m;  // fit=sphere
  FrameLayers layers = fitFrameLayers(s, &s.lights[0], m, s.camera);
  ASSERT_EQ(layers.layers.size(), 1u);
  EXPECT_EQ(layers.lightLayers, 1);
  EXPECT_TRUE(layers.depthClamp);
  EXPECT_TRUE(layers.cascadeSplitsView.empty());
  // Every corner of the scene's box lies inside the map (the sphere around the box contains it).
  for (int c = 0; c < 8; ++c) {
    glm::vec3 p((c & 1) ? 5.0f : -5.0f, (c & 2) ? 1.0f : 0.0f, (c & 4) ? 5.0f : -5.0f);
    glm::vec3 uvz = uvDepth(layers.layers[0].texFromWorld, p);
    EXPECT_GE(uvz.x, 0.0f) << c;
    EXPECT_LE(uvz.x, 1.0f) << c;
    EXPECT_GE(uvz.y, 0.0f) << c;
    EXPECT_LE(uvz.y, 1.0f) << c;
  }
  // Light straight down: the roof (y = 1) is nearer the light than the floor below it.
  EXPECT_LT(uvDepth(layers.layers[0].texFromWorld, {0, 1, 0}).z, uvDepth(layers.layers[0].texFromWorld, {0, 0, 0}).z);
  ResolveSpecialization spec = resolveSpecialization(s, &s.lights[0], m, layers);
  EXPECT_EQ(spec[raster::abi::kSpecAffine], 1u);  // orthographic
  EXPECT_EQ(spec[raster::abi::kSpecCascaded], 0u);
  EXPECT_EQ(spec[raster::abi::kSpecLightType], uint32_t(raster::abi::kLightDirectional));
}

TEST(RasterResolveParams, PointLightsFitSixFacesAndProjectorsFollowTheLight) {
  Scene s = roofScene();
  s.lights[0].type = LightType::Point;
  s.lights[0].position = {0, 4, 0};
  Projector p;
  p.name = "slide";
  p.position = {0, 5, 5};
  p.direction = glm::normalize(glm::vec3(0, -1, -1));
  s.projectors.push_back(p);
  Method m;
  FrameLayers layers = fitFrameLayers(s, &s.lights[0], m, s.camera);
  ASSERT_EQ(layers.layers.size(), 7u);
  EXPECT_EQ(layers.lightLayers, 6);
  // The projector's layer is its own projective texture matrix.
  const glm::mat4 expected = p.texFromWorld();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_FLOAT_EQ(layers.layers[6].texFromWorld[c][r], expected[c][r]);

  raster::abi::Params prm = packResolveParams(s, &s.lights[0], m, s.camera, layers, {{12, 4, 3}});
  EXPECT_EQ(prm.sizes, glm::ivec4(m.mapSize, 6, 1, m.filterSize));
  EXPECT_EQ(prm.projector[0], glm::ivec4(12, 4, 3, 6));  // first texel, width, height, its layer
  EXPECT_EQ(glm::vec3(prm.projectorPos[0]), p.position);
  EXPECT_EQ(prm.lightPosType, glm::vec4(0, 4, 0, float(raster::abi::kLightPoint)));
  ResolveSpecialization spec = resolveSpecialization(s, &s.lights[0], m, layers);
  EXPECT_EQ(spec[raster::abi::kSpecProjectorCount], 1u);
  EXPECT_EQ(spec[raster::abi::kSpecAffine], 0u);  // perspective faces
  EXPECT_EQ(spec[raster::abi::kSpecLightType], uint32_t(raster::abi::kLightPoint));
}

TEST(RasterResolveParams, MethodFieldsLandWhereTheShaderReadsThem) {
  Scene s = roofScene();
  Method m;
  m.mapSize = 1024;
  m.biasCompare = 0.002f;
  m.biasNormal = 1.5f;
  m.biasReceiverPlane = true;
  m.biasAdaptive = true;
  m.biasAdaptiveEpsilon = 0.03f;
  m.biasConstant = 2.0f;
  m.biasSlope = 3.0f;
  m.biasClamp = 0.01f;
  m.mapFormat = DepthFormat::D16;
  m.filter = Filter::Poisson;
  m.filterTaps = 24;
  m.filterRadius = 2.5f;
  m.projectorReverseGuard = false;
  FrameLayers layers = fitFrameLayers(s, &s.lights[0], m, s.camera);
  raster::abi::Params prm = packResolveParams(s, &s.lights[0], m, s.camera, layers, {});
  EXPECT_EQ(prm.bias, glm::vec4(0.002f, 1.5f, 1.0f, 2.5f));
  EXPECT_EQ(prm.adaptive, glm::vec4(0.03f, 0.0f, 0.0f, 0.0f));
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], m, layers)[raster::abi::kSpecAdaptive], 1u);
  m.biasAdaptive = false;
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], m, layers)[raster::abi::kSpecAdaptive], 0u);
  // The receiver plane and the normal offset switch their code on through specialization constants.
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], m, layers)[raster::abi::kSpecReceiverPlane], 1u);
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], m, layers)[raster::abi::kSpecNormalOffset], 1u);
  Method plain = m;
  plain.biasReceiverPlane = false;
  plain.biasNormal = 0.0f;
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], plain, layers)[raster::abi::kSpecReceiverPlane], 0u);
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], plain, layers)[raster::abi::kSpecNormalOffset], 0u);
  plain.biasNormal = -0.5f;  // any offset, either way
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], plain, layers)[raster::abi::kSpecNormalOffset], 1u);
  // pcf's size is compiled in (its loops unroll); every other filter shares the pipelines of 0.
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], plain, layers)[raster::abi::kSpecPcfSize], 0u);
  plain.filter = Filter::Pcf;
  plain.filterSize = 7;
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], plain, layers)[raster::abi::kSpecPcfSize], 7u);
  EXPECT_EQ(prm.depthBias, glm::vec4(2.0f, 3.0f, 0.01f, std::ldexp(1.0f, -16)));
  EXPECT_EQ(prm.sizes, glm::ivec4(1024, 1, 0, m.filterSize));
  EXPECT_EQ(prm.sizes2, glm::ivec4(160, 120, 24, 0));
  EXPECT_EQ(prm.lightDirCos, glm::vec4(0, -1, 0, std::cos(glm::radians(0.5f * s.lights[0].coneDeg))));
  EXPECT_EQ(prm.texFromWorld[0], layers.layers[0].texFromWorld);
  EXPECT_EQ(prm.layerInfo[0].x, layers.layers[0].texelWorldPerW);
  // The Poisson disc: unit-disc points, the same every time.
  for (int i = 0; i < raster::abi::kMaxTaps; ++i) {
    EXPECT_LE(glm::length(glm::vec2(prm.poisson[i])), 1.0f) << i;
    EXPECT_EQ(glm::vec2(prm.poisson[i]), poissonDisc()[size_t(i)]) << i;
  }
  ResolveSpecialization spec = resolveSpecialization(s, &s.lights[0], m, layers);
  EXPECT_EQ(spec[raster::abi::kSpecFilter], uint32_t(raster::abi::kFilterPoisson));
  EXPECT_EQ(spec[raster::abi::kSpecFloatDepth], 0u);
  m.mapFormat = DepthFormat::D32F;
  EXPECT_EQ(resolveSpecialization(s, &s.lights[0], m, layers)[raster::abi::kSpecFloatDepth], 1u);
  EXPECT_EQ(packResolveParams(s, &s.lights[0], m, s.camera, layers, {}).depthBias.w, 0.0f);
}

TEST(RasterResolveParams, RaysThroughPixelCentersMatchTheCamera) {
  Scene s = roofScene();
  Method m;
  FrameLayers layers = fitFrameLayers(s, &s.lights[0], m, s.camera);
  raster::abi::Params prm = packResolveParams(s, &s.lights[0], m, s.camera, layers, {});
  EXPECT_EQ(glm::vec3(prm.cameraOrigin), s.camera.position);
  // dir(x, y) = rayX x + rayY y + rayC points where Camera::rayDirection does.
  for (glm::vec2 xy : {glm::vec2(0.5f, 0.5f), glm::vec2(80.0f, 60.0f), glm::vec2(159.5f, 119.5f)}) {
    glm::vec3 d = glm::normalize(glm::vec3(prm.rayX) * xy.x + glm::vec3(prm.rayY) * xy.y + glm::vec3(prm.rayC));
    glm::vec3 expected = s.camera.rayDirection(xy.x, xy.y);
    EXPECT_NEAR(glm::dot(d, expected), 1.0f, 1e-6f) << xy.x << ", " << xy.y;
  }
}

TEST(RasterResolveParams, CascadesCarryTheirSplitsAndTheFitCameraShift) {
  Scene s = roofScene();
  Method m;
  m.fit = Fit::Cascades;
  m.cascadeCount = 3;
  m.cascadeBlend = 0.2f;
  Camera fit = s.camera;
  fit.position += glm::normalize(fit.lookAt - fit.position) * 0.5f;  // 0.5 further along its view
  FrameLayers layers = fitFrameLayers(s, &s.lights[0], m, fit);
  ASSERT_EQ(layers.lightLayers, 3);
  ASSERT_EQ(layers.cascadeSplitsView.size(), 4u);
  raster::abi::Params prm = packResolveParams(s, &s.lights[0], m, fit, layers, {});
  EXPECT_EQ(prm.cascadeView.w, 3.0f);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(prm.cascadeFar[i / 4][i % 4], layers.cascadeSplitsView[size_t(i) + 1]);
  EXPECT_EQ(prm.cascadeInfo.x, 0.2f);
  EXPECT_EQ(prm.cascadeInfo.y, layers.cascadeSplitsView[0]);
  EXPECT_NEAR(prm.cascadeInfo.z, -0.5f, 1e-5f);  // the eval camera sits 0.5 behind the fit camera
  ResolveSpecialization spec = resolveSpecialization(s, &s.lights[0], m, layers);
  EXPECT_EQ(spec[raster::abi::kSpecCascaded], 1u);
  EXPECT_EQ(spec[raster::abi::kSpecBlend], 1u);
}

TEST(RasterResolveParams, SpotAndNoLight) {
  Scene s = roofScene();
  s.lights[0] = spotAt({0, 5, 0}, {0, -1, 0}, 60.0f);
  Method m;
  FrameLayers layers = fitFrameLayers(s, &s.lights[0], m, s.camera);
  ASSERT_EQ(layers.lightLayers, 1);
  raster::abi::Params prm = packResolveParams(s, &s.lights[0], m, s.camera, layers, {});
  EXPECT_EQ(prm.lightPosType.w, float(raster::abi::kLightSpot));
  EXPECT_FLOAT_EQ(prm.lightDirCos.w, std::cos(glm::radians(30.0f)));
  // The spot's apex projects to the map's center.
  glm::vec3 below = uvDepth(layers.layers[0].texFromWorld, {0, 0, 0});
  EXPECT_NEAR(below.x, 0.5f, 1e-6f);
  EXPECT_NEAR(below.y, 0.5f, 1e-6f);

  FrameLayers none = fitFrameLayers(s, nullptr, m, s.camera);
  EXPECT_EQ(none.lightLayers, 0);
  EXPECT_TRUE(none.layers.empty());
  EXPECT_EQ(packResolveParams(s, nullptr, m, s.camera, none, {}).lightPosType.w, -1.0f);
  ResolveSpecialization spec = resolveSpecialization(s, nullptr, m, none);
  EXPECT_EQ(spec[raster::abi::kSpecLightType], uint32_t(raster::abi::kLightNone));
  EXPECT_EQ(spec[raster::abi::kSpecAffine], 0u);
}

// The kinds tables drive the enums, the keys and the shader codes: each row round-trips.
TEST(RasterResolveParams, KindTablesAgreeWithTheShaderCodes) {
  ASSERT_EQ(filterKinds().size(), 11u);
  for (const KindInfo<Filter>& k : filterKinds()) {
    EXPECT_EQ(toString(k.kind), k.key);
    Method m;
    applyMethodSetting(m, "filter", k.key, "--set");
    EXPECT_EQ(m.filter, k.kind);
    EXPECT_NE(std::string(k.help), "");
  }
  EXPECT_EQ(int(Filter::Pcf), raster::abi::kFilterPcf);
  EXPECT_EQ(int(Filter::Hw2x2), raster::abi::kFilterHw2x2);
  EXPECT_EQ(int(Filter::Vsm), raster::abi::kFilterVsm);
  EXPECT_EQ(int(Filter::Msm), raster::abi::kFilterMsm);
  // The filterable maps, and how many moments each stores (RG32F: 2, RGBA32F: 4).
  for (const KindInfo<Filter>& k : filterKinds())
    EXPECT_EQ(momentCount(k.kind), k.kind == Filter::Vsm || k.kind == Filter::Evsm2   ? 2
                                   : k.kind == Filter::Evsm4 || k.kind == Filter::Msm ? 4
                                                                                      : 0)
        << k.key;
  for (const KindInfo<Fit>& k : fitKinds()) EXPECT_EQ(toString(k.kind), k.key);
  EXPECT_EQ(kindKeys(lightTypeKinds()), "directional, spot, point");
  for (const KindInfo<LightType>& k : lightTypeKinds()) EXPECT_NE(int(k.kind), raster::abi::kLightNone);
}

}  // namespace raster_resolve_params_test
