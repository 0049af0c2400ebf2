// The soft truth of sized lights (reference/README.md, "Sized lights") against closed forms:
// - a sun of 12 degrees straight overhead, a horizontal disk above a ground plane: each ground pixel's
//   visible fraction against the solid-angle integral computed here in double precision, within
//   its vis_sigma, with the tail beyond 3 sigma counted;
// - a sphere occluder under a sphere light: umbra, penumbra and lit points from the angular radii
//   and the angle between the centers;
// - convergence: the RMSE against the integral shrinks as the light samples grow;
// - the same bits for any thread count and both SIMD compilations; hard lights untouched;
// - bad --light-samples / light_samples values exit 2 naming the option or the file and place.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"
#include "support/cli.h"

namespace reference_soft_test {

namespace {

using namespace shadowlab;
namespace fs = std::filesystem;

Scene sceneFromText(const std::string& name, const std::string& text) {
  const fs::path dir = shadowlab::testing::freshTempDir("reference_soft_" + name);
  const fs::path path = dir / (name + ".json");
  std::ofstream(path) << text;
  Scene scene = loadScene(path.string());
  fs::remove_all(dir);
  return scene;
}

// ---- (a) the disk under an overhead sun ------------------------------------------------------

constexpr double kDiskHeight = 2.0, kDiskRadius = 1.0;
constexpr double kSunDiameterDeg = 12.0;
constexpr int kDiskSegments = 4096;  // the inscribed 4096-gon is within 3e-7 of the circle

// Ground plane, a camera below the disk's height looking at its shadow, a 12-degree sun overhead,
// and the disk: a two-sided triangle fan of radius 1 at height 2 over the origin.
Scene diskScene(int width, int height) {
  Scene scene = sceneFromText("disk", R"({
    "camera": {"position": [0, 1.2, 4.5], "look_at": [0, 0, 0], "vfov_deg": 50, "width": 160, "height": 120},
    "objects": [{"type": "plane", "name": "ground", "size": [40, 40]}],
    "lights": [{"type": "directional", "name": "sun", "direction": [0, -1, 0], "angular_diameter_deg": 12}]
  })");
  scene.camera.width = width;
  scene.camera.height = height;
  Object disk;
  disk.name = "disk";
  disk.id = scene.objects.back().id + 1;
  disk.positions.push_back(glm::vec3(0.0f, float(kDiskHeight), 0.0f));
  for (int k = 0; k < kDiskSegments; ++k) {
    const double a = 2.0 * M_PI * k / kDiskSegments;
    disk.positions.push_back(
        glm::vec3(float(kDiskRadius * std::cos(a)), float(kDiskHeight), float(kDiskRadius * std::sin(a))));
    disk.triangles.push_back(glm::uvec3(0, 1 + k, 1 + (k + 1) % kDiskSegments));
    disk.triangleMaterial.push_back(0);
  }
  scene.objects.push_back(disk);
  return scene;
}

// The visible fraction of a sun of half angle alpha straight overhead, seen from the ground point at
// horizontal distance q from the disk's axis: 1 - (solid angle of the cap's directions that meet the
// disk) / (cap's solid angle). A direction at polar angle theta meets the disk's plane at horizontal
// offset rho = H tan(theta); the azimuths that land inside the disk are those with
// q^2 + rho^2 + 2 q rho cos(psi) <= R^2. Integrated over u = 1 - cos(theta) (uniform in solid
// angle) by the midpoint rule on 4000 intervals, in double.
double diskVisibleFraction(double q) {
  const double alpha = kSunDiameterDeg * 0.5 * M_PI / 180.0;
  const double rhoMax = kDiskHeight * std::tan(alpha);
  if (q + rhoMax <= kDiskRadius) return 0.0;
  if (q - rhoMax >= kDiskRadius) return 1.0;
  const double uMax = 1.0 - std::cos(alpha);
  constexpr int kSteps = 4000;
  double blocked = 0.0;
  for (int i = 0; i < kSteps; ++i) {
    const double u = (i + 0.5) / kSteps * uMax;
    const double cosTheta = 1.0 - u;
    const double rho = kDiskHeight * std::sqrt(1.0 - cosTheta * cosTheta) / cosTheta;
    double inside;  // fraction of azimuths inside the disk
    if (q + rho <= kDiskRadius) {
      inside = 1.0;
    } else if (std::fabs(q - rho) >= kDiskRadius) {
      inside = 0.0;
    } else {
      const double c = (kDiskRadius * kDiskRadius - q * q - rho * rho) / (2.0 * q * rho);
      inside = c >= 1.0 ? 1.0 : c <= -1.0 ? 0.0 : 1.0 - std::acos(c) / M_PI;
    }
    blocked += inside;
  }
  return 1.0 - blocked / kSteps;
}

struct DiskCheck {
  size_t ground = 0, penumbra = 0, outside2 = 0, outside3 = 0, exactWrong = 0;
  double sumSquared = 0.0;  // over penumbra pixels
  double rmse() const { return penumbra ? std::sqrt(sumSquared / double(penumbra)) : 0.0; }
};

DiskCheck checkDisk(const Scene& scene, const Frame& frame) {
  const auto& objectId = frame.get("object_id");
  const auto& px = frame.get("P.x");
  const auto& pz = frame.get("P.z");
  const auto& vis = frame.get("light.sun.vis");
  const auto& sigma = frame.get("light.sun.vis_sigma");
  const uint32_t ground = scene.objects.front().id;
  DiskCheck check;
  for (size_t i = 0; i < vis.size(); ++i) {
    if (uint32_t(objectId[i]) != ground) continue;
    ++check.ground;
    const double expected = diskVisibleFraction(std::hypot(double(px[i]), double(pz[i])));
    const double error = double(vis[i]) - expected;
    if (expected == 0.0 || expected == 1.0) {
      // Umbra and full light: every sample agrees, exactly (the ground point lies more than 1e-4
      // inside either region for all but a handful of pixels, which the margin below allows).
      if (std::fabs(error) > 0.0) ++check.exactWrong;
      continue;
    }
    ++check.penumbra;
    check.sumSquared += error * error;
    EXPECT_GT(sigma[i], 0.0f) << "pixel " << i;
    if (std::fabs(error) > 2.0 * sigma[i]) ++check.outside2;
    if (std::fabs(error) > 3.0 * sigma[i]) ++check.outside3;
  }
  return check;
}

Frame renderDisk(const Scene& scene, int lightSamples, ReferenceChannels channels = ReferenceChannels::All) {
  ReferenceOptions options;
  options.lightSamples = lightSamples;
  options.channels = channels;
  return renderReference(scene, options);
}

TEST(ReferenceSoft, SunOverDiskMatchesTheSolidAngleIntegralWithinSigma) {
  const Scene scene = diskScene(240, 180);
  const Frame frame = renderDisk(scene, 64);
  const DiskCheck check = checkDisk(scene, frame);
  std::printf(
      "disk, 64 light samples: %zu ground pixels, %zu in the penumbra, %zu beyond 2 sigma, %zu beyond 3 "
      "sigma, RMSE %.5f, %zu exact pixels wrong\n",
      check.ground, check.penumbra, check.outside2, check.outside3, check.rmse(), check.exactWrong);
  EXPECT_GT(check.ground, 10000u);
  EXPECT_GT(check.penumbra, 1000u);  // not vacuous: the penumbra ring is well sampled by pixels
  // A Gaussian error would put 4.6% beyond 2 sigma and 0.27% beyond 3; vis_sigma is a conservative
  // bound (stratified sampling's error is smaller than the binomial's), so fewer lie beyond.
  EXPECT_LE(double(check.outside2), 0.046 * double(check.penumbra));
  EXPECT_LE(double(check.outside3), 0.0027 * double(check.penumbra) + 2.0);
  EXPECT_LE(check.exactWrong, 2u);
  // The sigma channel is in the Compare set too, with the same values.
  const Frame compare = renderDisk(scene, 64, ReferenceChannels::Compare);
  EXPECT_EQ(compare.get("light.sun.vis_sigma"), frame.get("light.sun.vis_sigma"));
  EXPECT_EQ(compare.get("light.sun.vis"), frame.get("light.sun.vis"));
  EXPECT_EQ(frame.meta.at("light_samples"), 64);
}

// Convergence: the RMSE over the penumbra against the integral, as the light samples grow 4x each
// step. Stratified sampling of a region with a smooth edge converges about as N^-3/4 (2.8x per 4x).
TEST(ReferenceSoft, RmseShrinksAsLightSamplesGrow) {
  const Scene scene = diskScene(160, 120);
  double previous = 1.0;
  std::printf("| light samples | penumbra pixels | RMSE | mean vis_sigma | beyond 3 sigma |\n|---|---|---|---|---|\n");
  for (int samples : {16, 64, 256, 1024}) {
    const Frame frame = renderDisk(scene, samples);
    const DiskCheck check = checkDisk(scene, frame);
    const auto& sigma = frame.get("light.sun.vis_sigma");
    const auto& objectId = frame.get("object_id");
    double sigmaSum = 0.0;
    size_t sigmaCount = 0;
    for (size_t i = 0; i < sigma.size(); ++i) {
      if (uint32_t(objectId[i]) != scene.objects.front().id) continue;
      const float v = frame.get("light.sun.vis")[i];
      if (v > 0.0f && v < 1.0f) {
        sigmaSum += sigma[i];
        ++sigmaCount;
      }
    }
    std::printf("| %d | %zu | %.5f | %.5f | %zu |\n", samples, check.penumbra, check.rmse(),
                sigmaCount ? sigmaSum / double(sigmaCount) : 0.0, check.outside3);
    EXPECT_LT(check.rmse(), 0.6 * previous) << samples << " light samples";
    previous = check.rmse();
  }
  EXPECT_LT(previous, 0.01);
}

// ---- (b) a sphere occluder under a sphere light -----------------------------------------------

TEST(ReferenceSoft, SphereUnderSphereLightHasUmbraPenumbraAndLitWhereTheAnglesSay) {
  // The occluder: the loader's sphere at 512 x 256 (its inscribed facets lie within 2e-5 of the
  // sphere: the margin below covers them and the shadow origin's offset many times over).
  const Scene scene = sceneFromText("spheres", R"({
    "camera": {"position": [0, 3.2, 3.6], "look_at": [0.3, 0, 0], "vfov_deg": 50, "width": 200, "height": 150},
    "objects": [
      {"type": "plane", "name": "ground", "size": [40, 40]},
      {"type": "sphere", "name": "ball", "radius": 0.5, "segments": 512, "rings": 256,
       "transform": {"translate": [0, 1, 0]}}
    ],
    "lights": [{"type": "point", "name": "bulb", "position": [0.6, 5, -0.3], "radius": 0.8}]
  })");
  const Light& light = scene.lights.front();
  const glm::dvec3 lightCenter(light.position), ballCenter(0.0, 1.0, 0.0);
  const double lightRadius = light.radius, ballRadius = 0.5;
  ReferenceOptions options;
  options.lightSamples = 256;
  const Frame frame = renderReference(scene, options);
  const auto& objectId = frame.get("object_id");
  const auto& vis = frame.get("light.bulb.vis");
  const auto& sigma = frame.get("light.bulb.vis_sigma");
  const float* p[3] = {frame.get("P.x").data(), frame.get("P.y").data(), frame.get("P.z").data()};
  const uint32_t ground = scene.objects.front().id;
  // Margins, in radians of the angle between the centers: 1e-3 around the umbra's and the light's
  // edge for the exact classes; a penumbra point is checked for 0 < vis < 1 only where it is at
  // least a fifth of the light's angular diameter from both edges (nearer an edge the light's
  // covered part, or its uncovered part, may fall between the 256 samples).
  constexpr double kExactMargin = 1e-3, kPenumbraBand = 0.2;
  size_t umbra = 0, lit = 0, penumbra = 0, wrong = 0;
  std::string first;
  for (size_t i = 0; i < vis.size(); ++i) {
    if (uint32_t(objectId[i]) != ground) continue;
    const glm::dvec3 point(p[0][i], p[1][i], p[2][i]);
    const glm::dvec3 toLight = lightCenter - point, toBall = ballCenter - point;
    const double alphaLight = std::asin(lightRadius / glm::length(toLight));
    const double alphaBall = std::asin(ballRadius / glm::length(toBall));
    const double gamma = std::acos(std::clamp(glm::dot(glm::normalize(toLight), glm::normalize(toBall)), -1.0, 1.0));
    const double umbraEdge = alphaBall - alphaLight;  // gamma below: the light's disc inside the ball's
    const double litEdge = alphaBall + alphaLight;    // gamma above: the discs apart
    const double band = kPenumbraBand * 2.0 * alphaLight;
    bool ok = true;
    const char* expected = nullptr;
    if (gamma <= umbraEdge - kExactMargin) {
      ++umbra;
      ok = vis[i] == 0.0f;
      expected = "umbra (0)";
    } else if (gamma >= litEdge + kExactMargin) {
      ++lit;
      ok = vis[i] == 1.0f;
      expected = "lit (1)";
    } else if (gamma >= umbraEdge + band && gamma <= litEdge - band) {
      ++penumbra;
      ok = vis[i] > 0.0f && vis[i] < 1.0f && sigma[i] > 0.0f;
      expected = "penumbra (0 < vis < 1)";
    } else {
      continue;
    }
    if (!ok && wrong++ == 0)
      first = "pixel " + std::to_string(i) + ": vis " + std::to_string(vis[i]) + ", expected " + expected;
  }
  std::printf("sphere light: %zu umbra, %zu penumbra, %zu lit ground pixels checked\n", umbra, penumbra, lit);
  EXPECT_EQ(wrong, 0u) << first;
  EXPECT_GT(umbra, 300u);
  EXPECT_GT(penumbra, 600u);
  EXPECT_GT(lit, 5000u);
}

// ---- (d) determinism --------------------------------------------------------------------------

Scene softLightsScene() {
  Scene scene = loadScene(resolveScenePath("sphere_on_plane"), {{"/camera/width", 120}, {"/camera/height", 68}});
  scene.lights.front().angularDiameterDeg = 6.0f;
  Light spot;
  spot.name = "spot";
  spot.type = LightType::Spot;
  spot.position = {0.5f, 6.0f, 0.3f};
  spot.direction = glm::normalize(glm::vec3(-0.1f, -1.0f, -0.05f));
  spot.coneDeg = 50.0f;
  spot.radius = 0.7f;
  Light point;
  point.name = "point";
  point.type = LightType::Point;
  point.position = {3.0f, 4.0f, 2.0f};
  point.radius = 1.5f;
  Light hard;  // a hard light beside the sized ones keeps its own channels
  hard.name = "hard";
  hard.type = LightType::Point;
  hard.position = {-3.0f, 4.0f, 1.0f};
  scene.lights.push_back(spot);
  scene.lights.push_back(point);
  scene.lights.push_back(hard);
  return scene;
}

void expectSameBits(const Frame& a, const Frame& b) {
  ASSERT_EQ(a.names, b.names);
  for (size_t k = 0; k < a.names.size(); ++k)
    EXPECT_EQ(std::memcmp(a.data[k].data(), b.data[k].data(), a.data[k].size() * sizeof(float)), 0)
        << "channel " << a.names[k];
}

TEST(ReferenceSoft, SameBitsForAnyThreadCountAndBothSimdCompilations) {
  const Scene scene = softLightsScene();
  for (int spp : {1, 4, 3}) {
    SCOPED_TRACE("spp " + std::to_string(spp));
    ReferenceOptions options;
    options.spp = spp;
    options.lightSamples = spp == 1 ? 37 : 16;  // 37: one stratum across, a partial last packet
    options.threads = 1;
    options.simd = ReferenceSimd::Baseline;
    ReferenceStats oneStats;
    std::vector<uint8_t> onePicture;
    const Frame one = renderReference(scene, options, &oneStats, &onePicture);
    for (int threads : {0, 2, 4}) {
      options.threads = threads;
      ReferenceStats stats;
      std::vector<uint8_t> picture;
      expectSameBits(renderReference(scene, options, &stats, &picture), one);
      EXPECT_EQ(stats.shadowRays, oneStats.shadowRays);
      EXPECT_EQ(picture, onePicture);
    }
    if (referenceHasAvx2()) {
      options.simd = ReferenceSimd::Avx2;
      std::vector<uint8_t> picture;
      expectSameBits(renderReference(scene, options, nullptr, &picture), one);
      EXPECT_EQ(picture, onePicture);
    }
    // Not vacuous: each sized light has penumbra pixels, and the picture comes from the frame.
    for (const char* name : {"sun", "spot", "point"}) {
      const auto& vis = one.get(std::string("light.") + name + ".vis");
      const size_t soft = size_t(std::count_if(vis.begin(), vis.end(), [](float v) { return v > 0.0f && v < 1.0f; }));
      EXPECT_GT(soft, 40u) << name;
    }
    EXPECT_EQ(onePicture, referencePicture(scene, one));
  }
}

// ---- (e) hard lights untouched; the channel set; the cache key --------------------------------

TEST(ReferenceSoft, HardLightsKeepTheirChannelsValuesAndCacheKey) {
  Scene scene = loadScene(resolveScenePath("sphere_on_plane"), {{"/camera/width", 120}, {"/camera/height", 68}});
  ReferenceOptions options;
  options.spp = 2;
  options.lightSamples = 1;
  const Frame one = renderReference(scene, options);
  options.lightSamples = 4096;
  const Frame many = renderReference(scene, options);
  expectSameBits(one, many);
  EXPECT_EQ(one.names, referenceChannelNames(scene, ReferenceChannels::All));
  EXPECT_EQ(std::count(one.names.begin(), one.names.end(), "light.sun.vis_sigma"), 0);
  EXPECT_FALSE(one.meta.contains("light_samples"));
  // The cache key of a hard scene is the one it always had (the light samples leave it alone).
  const std::string key = "shadowlab.reference/2;scene=" + scene.hash + ";camera=" + scene.camera.hash() + ";spp=2";
  EXPECT_EQ(referenceHash(scene, options), hashHex(fnv1a64(key.data(), key.size())));
  // A sized light: the channel appears (Compare and All), the samples enter the key.
  scene.lights.front().angularDiameterDeg = 2.0f;
  const std::vector<std::string> compare = referenceChannelNames(scene, ReferenceChannels::Compare);
  EXPECT_EQ(compare, (std::vector<std::string>{"hit", "object_id", "light.sun.vis", "light.sun.occluder_dist",
                                               "light.sun.vis_sigma"}));
  const std::string sized = referenceHash(scene, options);
  EXPECT_NE(sized, hashHex(fnv1a64(key.data(), key.size())));
  options.lightSamples = 64;
  EXPECT_NE(referenceHash(scene, options), sized);
  // A point inside a sphere light is fully lit, exactly, with no uncertainty.
  Scene inside = loadScene(resolveScenePath("sphere_on_plane"), {{"/camera/width", 64}, {"/camera/height", 36}});
  inside.lights.front().type = LightType::Point;
  inside.lights.front().position = {0.0f, 0.0f, 0.0f};
  inside.lights.front().radius = 1000.0f;
  const Frame insideFrame = renderReference(inside, options);
  const auto& hit = insideFrame.get("hit");
  const auto& vis = insideFrame.get("light.sun.vis");
  const auto& sigma = insideFrame.get("light.sun.vis_sigma");
  const auto& distance = insideFrame.get("light.sun.occluder_dist");
  for (size_t i = 0; i < hit.size(); ++i) {
    if (hit[i] != 1.0f) continue;
    ASSERT_EQ(vis[i], 1.0f) << i;
    ASSERT_EQ(sigma[i], 0.0f) << i;
    ASSERT_EQ(distance[i], -1.0f) << i;
  }
}

// A pixel whose light samples all agree still gets a sigma above 0 (the estimate cannot tell a
// fraction within about 1/N of 0 or 1 from 0 or 1); a fully deterministic one (facing away from
// the whole light, no hit) gets 0.
TEST(ReferenceSoft, SigmaIsPositiveWhereTheSamplesAllAgree) {
  const Scene scene = diskScene(96, 72);
  ReferenceOptions options;
  options.lightSamples = 64;
  const Frame frame = renderReference(scene, options);
  const auto& vis = frame.get("light.sun.vis");
  const auto& sigma = frame.get("light.sun.vis_sigma");
  const auto& objectId = frame.get("object_id");
  size_t agreeing = 0;
  for (size_t i = 0; i < vis.size(); ++i) {
    if (uint32_t(objectId[i]) != scene.objects.front().id) continue;
    if (vis[i] == 0.0f || vis[i] == 1.0f) {
      ++agreeing;
      // sqrt(p (1 - p) / N) with p = 0.5 / (N + 1): 0.01095 at N = 64.
      EXPECT_NEAR(sigma[i], std::sqrt(0.5 / 65.0 * (1.0 - 0.5 / 65.0) / 64.0), 1e-6) << i;
    }
  }
  EXPECT_GT(agreeing, 1000u);
  const auto& hit = frame.get("hit");
  for (size_t i = 0; i < hit.size(); ++i)
    if (hit[i] == 0.0f) {
      ASSERT_EQ(sigma[i], 0.0f);
    }
}

// ---- the bundled soft_post -------------------------------------------------------------------

// soft_post's shadow hardens toward the post's foot: the umbra (vis 0) lies only near it, and
// farther away the shadow's darkest and mean visibility rise (the penumbra spreads the post's
// shadow over a wider, lighter band).
TEST(ReferenceSoft, SoftPostPenumbraWidensAwayFromTheContact) {
  const Scene scene = loadScene(resolveScenePath("soft_post"));
  ASSERT_TRUE(scene.lights.front().sized());
  ReferenceOptions options;
  const Frame frame = renderReference(scene, options);
  const auto& objectId = frame.get("object_id");
  const auto& vis = frame.get("light.bulb.vis");
  const auto& px = frame.get("P.x");
  const auto& pz = frame.get("P.z");
  const uint32_t ground = scene.objects.front().id;
  constexpr int kBins = 4;  // distance from the post's axis: [0.1, 0.9), [0.9, 1.7), [1.7, 2.5), [2.5, 3.3)
  size_t shadowed[kBins] = {}, umbra[kBins] = {};
  double sum[kBins] = {}, darkest[kBins] = {1, 1, 1, 1};
  for (size_t i = 0; i < vis.size(); ++i) {
    if (uint32_t(objectId[i]) != ground || vis[i] == 1.0f) continue;
    const double distance = std::hypot(double(px[i]), double(pz[i]));
    const int bin = int(std::floor((distance - 0.1) / 0.8));
    if (bin < 0 || bin >= kBins) continue;
    ++shadowed[bin];
    sum[bin] += vis[i];
    darkest[bin] = std::min(darkest[bin], double(vis[i]));
    if (vis[i] == 0.0f) ++umbra[bin];
  }
  double previousMean = -1.0, previousDarkest = -1.0;
  for (int b = 0; b < kBins; ++b) {
    ASSERT_GT(shadowed[b], 100u) << "bin " << b;
    const double mean = sum[b] / double(shadowed[b]);
    std::printf("soft_post, %.1f..%.1f from the post: %zu shadowed pixels, mean vis %.3f, darkest %.3f, umbra %zu\n",
                0.1 + 0.8 * b, 0.9 + 0.8 * b, shadowed[b], mean, darkest[b], umbra[b]);
    EXPECT_GT(mean, previousMean) << "bin " << b;
    EXPECT_GT(darkest[b], previousDarkest) << "bin " << b;
    previousMean = mean;
    previousDarkest = darkest[b];
  }
  EXPECT_GT(umbra[0], 50u);
  for (int b = 1; b < kBins; ++b) EXPECT_EQ(umbra[b], 0u) << "bin " << b;
}

// ---- bad values through the real binary -------------------------------------------------------

TEST(ReferenceSoft, BadLightSamplesExitTwoNamingTheOptionOrTheFile) {
  const fs::path dir = shadowlab::testing::freshTempDir("reference_soft_cli");
  for (const char* value : {"0", "4097", "-5"}) {
    SCOPED_TRACE(value);
    const fs::path out = dir / "out";
    const auto run = shadowlab::testing::runShadowlab(
        std::string("reference sphere_on_plane -o '") + out.string() + "' --light-samples " + value, dir);
    EXPECT_EQ(run.code, 2) << run.err;
    EXPECT_NE(run.err.find("--light-samples: error: got " + std::string(value) + "; expected an integer 1..4096"),
              std::string::npos)
        << run.err;
    EXPECT_FALSE(fs::exists(out));
    for (const char* command : {"run", "sweep", "tune"}) {
      const auto other = shadowlab::testing::runShadowlab(
          std::string(command) + " sphere_on_plane -o '" + out.string() + "' --light-samples " + value, dir);
      EXPECT_EQ(other.code, 2) << command << ": " << other.err;
      EXPECT_NE(other.err.find("--light-samples: error: got " + std::string(value)), std::string::npos)
          << command << ": " << other.err;
      EXPECT_FALSE(fs::exists(out)) << command;
    }
  }
  // The sweep file's key: the file and the JSON pointer.
  for (const char* value : {"0", "5000", "2.5", "\"64\""}) {
    SCOPED_TRACE(value);
    const fs::path sweep = dir / "bad.sweep.json";
    std::ofstream(sweep) << "{\"scenes\": [\"sphere_on_plane\"], \"light_samples\": " << value << "}";
    const fs::path out = dir / "out";
    const auto run =
        shadowlab::testing::runShadowlab("sweep --sweep '" + sweep.string() + "' -o '" + out.string() + "'", dir);
    EXPECT_EQ(run.code, 2) << run.err;
    EXPECT_NE(run.err.find(sweep.string() + ": /light_samples: error: got"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find("expected an integer 1..4096"), std::string::npos) << run.err;
    EXPECT_FALSE(fs::exists(out));
  }
  fs::remove_all(dir);
}

}  // namespace

}  // namespace reference_soft_test
