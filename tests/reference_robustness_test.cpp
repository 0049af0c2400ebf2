// The reference's own errors: self-shadowing (acne in the ground truth), leaks from the origin
// offset at contact lines and through thin walls, and results that depend on the thread count.
//
// Convex casters (the bundled scenes' boxes, rotated or not) are described exactly by the face
// planes of their triangles. A ground point P under a directional light (toLight = -direction) is
//   shadowed  iff the ray P + s toLight, s > 0, enters the box (clipping the ray against every
//             face half-space leaves a non-empty interval),
// and that is the expected answer, except for points whose ray passes within `margin` world units
// of the box surface (it hits the box grown by margin but misses it shrunk by margin): those are
// left out. margin = 1e-3 is far below a pixel's footprint (~1e-2 here) and far above the shadow
// origin's offset (2^-17 of the coordinates, ~1e-4), so an offset that leaked light at contact
// lines or through thin walls, or a self-intersection that darkened the ground, would fail.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/glm.hpp>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"

namespace reference_robustness_test {

namespace {

using namespace shadowlab;

struct ConvexCaster {
  std::vector<glm::dvec3> normals;  // outward, unit
  std::vector<double> offsets;      // n . x <= offset inside

  // Face planes of a closed convex mesh, oriented away from its vertex centroid.
  explicit ConvexCaster(const Object& object) {
    glm::dvec3 centroid(0.0);
    for (const glm::vec3& p : object.positions) centroid += glm::dvec3(p);
    centroid /= double(object.positions.size());
    for (const glm::uvec3& tri : object.triangles) {
      const glm::dvec3 p0(object.positions[tri.x]), p1(object.positions[tri.y]), p2(object.positions[tri.z]);
      glm::dvec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
      if (glm::dot(n, p0 - centroid) < 0.0) n = -n;
      normals.push_back(n);
      offsets.push_back(glm::dot(n, p0));
    }
  }
  // Does the ray o + s d (s > 0) enter the body grown by `margin` (shrunk where negative)?
  bool hit(const glm::dvec3& o, const glm::dvec3& d, double margin) const {
    double enter = 0.0, leave = INFINITY;
    for (size_t k = 0; k < normals.size(); ++k) {
      const double distance = glm::dot(normals[k], o) - (offsets[k] + margin);
      const double along = glm::dot(normals[k], d);
      if (along == 0.0) {
        if (distance > 0.0) return false;
        continue;
      }
      const double s = -distance / along;
      if (along < 0.0) enter = std::max(enter, s);
      else leave = std::min(leave, s);
      if (enter > leave) return false;
    }
    return true;
  }
};

struct GroundCheck {
  size_t lit = 0, shadowed = 0, skipped = 0, wrongLit = 0, wrongShadowed = 0;
  std::string first;
};

// Every ground pixel whose expected answer is clear must match exactly.
GroundCheck checkGround(const Scene& scene, const Frame& frame, double margin = 1e-3) {
  const Object* ground = nullptr;
  std::vector<ConvexCaster> casters;
  for (const Object& object : scene.objects) {
    if (object.name == "ground") ground = &object;
    else casters.emplace_back(object);
  }
  EXPECT_NE(ground, nullptr);
  const Light& light = scene.lights.at(0);
  EXPECT_EQ(light.type, LightType::Directional);
  const glm::dvec3 toLight = -glm::normalize(glm::dvec3(light.direction));
  const std::string visName = "light." + light.name + ".vis";
  const auto& id = frame.get("object_id");
  const auto& vis = frame.get(visName);
  const auto& px = frame.get("P.x");
  const auto& py = frame.get("P.y");
  const auto& pz = frame.get("P.z");
  GroundCheck result;
  for (size_t i = 0; i < frame.pixelCount(); ++i) {
    if (!ground || id[i] != float(ground->id)) continue;
    const glm::dvec3 p(px[i], py[i], pz[i]);
    bool surely = false, maybe = false;
    for (const ConvexCaster& caster : casters) {
      surely = surely || caster.hit(p, toLight, -margin);
      maybe = maybe || caster.hit(p, toLight, margin);
    }
    if (maybe && !surely) {
      ++result.skipped;
      continue;
    }
    const bool expectedLit = !maybe;
    if (expectedLit) ++result.lit;
    else ++result.shadowed;
    if ((vis[i] == 1.0f) != expectedLit || (vis[i] != 0.0f && vis[i] != 1.0f)) {
      (expectedLit ? result.wrongShadowed : result.wrongLit)++;
      if (result.wrongLit + result.wrongShadowed <= 10)
        result.first += "  pixel " + std::to_string(i % frame.width) + ", " + std::to_string(i / frame.width) +
                        " at (" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) +
                        "): vis " + std::to_string(vis[i]) + "; expected " + (expectedLit ? "1" : "0") + "\n";
    }
  }
  return result;
}

// The grazing scene at its own 5 degrees and lower: the ground facing the light at 5, 1 and
// 0.25 degrees must be lit everywhere the block's shadow is not. Self-intersection would darken
// the ground (the classic acne, here in the reference itself): wrongShadowed counts it.
TEST(ReferenceRobustness, GrazingLightShowsZeroSelfShadowing) {
  for (double elevationDeg : {5.0, 1.0, 0.25}) {
    SCOPED_TRACE("elevation " + std::to_string(elevationDeg));
    const Scene scene = loadScene(resolveScenePath("grazing"), {{"/lights/0/elevation_deg", elevationDeg}});
    const Frame frame = renderReference(scene, {});
    const GroundCheck result = checkGround(scene, frame);
    EXPECT_EQ(result.wrongShadowed, 0u) << "self-shadowed ground pixels:\n" << result.first;
    EXPECT_EQ(result.wrongLit, 0u) << result.first;
    EXPECT_GT(result.lit, 100000u);
    EXPECT_GT(result.shadowed, 1000u);
  }
}

// Contact: the crate rests exactly on the ground (and at 0.002 and 0.01 above it). Points next
// to its base on the shadow side must stay dark: an origin offset large enough to slip under
// the crate would light them (wrongLit).
TEST(ReferenceRobustness, ContactLineDoesNotLeak) {
  for (double centerY : {1.0, 1.002, 1.01}) {
    SCOPED_TRACE("crate center y " + std::to_string(centerY));
    const Scene scene = loadScene(resolveScenePath("contact"), {{"/objects/1/transform/translate/1", centerY}});
    const Frame frame = renderReference(scene, {});
    const GroundCheck result = checkGround(scene, frame);
    EXPECT_EQ(result.wrongLit, 0u) << "leaking pixels:\n" << result.first;
    EXPECT_EQ(result.wrongShadowed, 0u) << result.first;
    EXPECT_GT(result.shadowed, 10000u);
    EXPECT_GT(result.lit, 100000u);
  }
}

// Thin walls down to 0.005 thick must block the light completely.
TEST(ReferenceRobustness, ThinWallDoesNotLeak) {
  for (double thickness : {0.02, 0.005}) {
    SCOPED_TRACE("thickness " + std::to_string(thickness));
    const Scene scene = loadScene(resolveScenePath("thin_wall"), {{"/objects/1/size/0", thickness}});
    const Frame frame = renderReference(scene, {});
    const GroundCheck result = checkGround(scene, frame);
    EXPECT_EQ(result.wrongLit, 0u) << "leaking pixels:\n" << result.first;
    EXPECT_EQ(result.wrongShadowed, 0u) << result.first;
    EXPECT_GT(result.shadowed, 20000u);
  }
}

// Bit-identical channels and metadata for 1, 2 and 4 threads (and a repeat), on scenes that
// exercise every path: a scanned mesh, alpha testing, a projector, and spp > 1.
TEST(ReferenceRobustness, BitIdenticalForAnyThreadCount) {
  struct Case {
    const char* scene;
    int spp;
  };
  for (const Case& c : {Case{"bunny", 1}, Case{"alpha_fence", 1}, Case{"projector", 1}, Case{"contact", 4}}) {
    SCOPED_TRACE(std::string(c.scene) + " spp " + std::to_string(c.spp));
    const Scene scene = loadScene(resolveScenePath(c.scene), {{"/camera/width", 480}, {"/camera/height", 270}});
    std::vector<Frame> frames;
    for (int threads : {1, 2, 4, 4}) {
      ReferenceOptions options;
      options.threads = threads;
      options.spp = c.spp;
      frames.push_back(renderReference(scene, options));
    }
    const Frame& first = frames.front();
    // The frame is not trivially constant: something is lit and something is shadowed.
    const auto& vis = first.get("light." + scene.lights.at(0).name + ".vis");
    const auto& hit = first.get("hit");
    size_t lit = 0, dark = 0;
    for (size_t i = 0; i < vis.size(); ++i) {
      if (hit[i] == 0.0f) continue;
      (vis[i] > 0.5f ? lit : dark)++;
    }
    EXPECT_GT(lit, 1000u);
    EXPECT_GT(dark, 500u);
    for (size_t f = 1; f < frames.size(); ++f) {
      ASSERT_EQ(frames[f].names, first.names);
      EXPECT_EQ(frames[f].meta, first.meta);
      for (size_t c2 = 0; c2 < first.names.size(); ++c2) {
        const auto& a = first.data[c2];
        const auto& b = frames[f].data[c2];
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0)
            << "channel " << first.names[c2] << " differs between 1 thread and run " << f;
      }
    }
  }
}

// The Compare channel set (what the reference cache holds) is the All set's channels, bit for bit,
// in the same order, on every bundled scene at its own size (spp 1), and at spp 4 on the scenes
// with alpha testing and a projector; the Compare frames with 2 threads, the All frames with 1.
TEST(ReferenceRobustness, CompareSetEqualsAllSetOnEveryBundledScene) {
  struct Case {
    std::string scene;
    int spp;
  };
  std::vector<Case> cases;
  for (const std::string& name : bundledSceneNames()) cases.push_back({name, 1});
  cases.push_back({"alpha_fence", 4});
  cases.push_back({"projector", 4});
  ASSERT_GE(cases.size(), 10u);
  for (const Case& c : cases) {
    SCOPED_TRACE(c.scene + " spp " + std::to_string(c.spp));
    Scene scene = loadScene(resolveScenePath(c.scene));
    if (c.spp > 1) scene = loadScene(resolveScenePath(c.scene), {{"/camera/width", 240}, {"/camera/height", 135}});
    ReferenceOptions options;
    options.spp = c.spp;
    options.threads = 1;
    options.channels = ReferenceChannels::All;
    const Frame all = renderReference(scene, options);
    options.threads = 2;
    options.channels = ReferenceChannels::Compare;
    const Frame compareSet = renderReference(scene, options);
    EXPECT_EQ(all.names, referenceChannelNames(scene, ReferenceChannels::All));
    EXPECT_EQ(compareSet.names, referenceChannelNames(scene, ReferenceChannels::Compare));
    EXPECT_EQ(all.meta.at("channels"), "all");
    EXPECT_EQ(compareSet.meta.at("channels"), "compare");
    nlohmann::json meta = compareSet.meta;
    meta["channels"] = "all";
    EXPECT_EQ(meta, all.meta);
    // Compare = hit, object_id, then per light vis and occluder_dist (and vis_sigma for a sized
    // light), per projector coverage, R, G, B.
    const size_t sizedLights = size_t(
        std::count_if(scene.lights.begin(), scene.lights.end(), [](const Light& light) { return light.sized(); }));
    const size_t expectedCount = 2 + 2 * scene.lights.size() + sizedLights + 4 * scene.projectors.size();
    ASSERT_EQ(compareSet.names.size(), expectedCount);
    EXPECT_EQ(all.names.size(), expectedCount + 7 + 2 * scene.projectors.size());
    size_t from = 0;
    for (size_t k = 0; k < compareSet.names.size(); ++k) {
      const std::string& name = compareSet.names[k];
      while (from < all.names.size() && all.names[from] != name) ++from;  // the same order
      ASSERT_LT(from, all.names.size()) << name << " missing or out of order in the All set";
      const auto& a = all.data[from];
      const auto& b = compareSet.data[k];
      ASSERT_EQ(a.size(), b.size());
      EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << "channel " << name;
    }
    // Not trivially equal: every scene has something hit and something that is not lit.
    size_t hits = 0;
    for (float h : compareSet.get("hit")) hits += h == 1.0f;
    EXPECT_GT(hits, 0u);
    EXPECT_LT(hits, compareSet.pixelCount());
  }
}

// The AVX2 compilation of the trace (ReferenceSimd::Avx2, what Auto runs on a CPU with AVX2) gives
// the baseline compilation's bits: every channel, the picture and the ray counts, on every bundled
// scene at its own size (All set, spp 1), at spp 3 (Hammersley) and 4 (grid) on the scenes with
// alpha testing and a projector, and with a spot and a point light added (spp 2) on four scenes.
// Skipped where the build or the CPU has no AVX2 (there only the baseline runs).
TEST(ReferenceRobustness, Avx2TraceEqualsBaselineOnEveryBundledScene) {
  if (!referenceHasAvx2()) GTEST_SKIP() << "no AVX2 trace in this build or on this CPU";
  struct Case {
    std::string scene;
    int spp;
    bool addLights;
  };
  std::vector<Case> cases;
  for (const std::string& name : bundledSceneNames()) cases.push_back({name, 1, false});
  for (const char* name : {"alpha_fence", "projector"})
    for (int spp : {3, 4}) cases.push_back({name, spp, false});
  for (const char* name : {"sphere_on_plane", "contact", "alpha_fence", "projector"}) cases.push_back({name, 2, true});
  ASSERT_GE(cases.size(), 14u);
  size_t spotLit = 0, spotDark = 0, pointLit = 0, pointDark = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.scene + " spp " + std::to_string(c.spp) + (c.addLights ? " with a spot and a point light" : ""));
    Scene scene = c.spp == 1 ? loadScene(resolveScenePath(c.scene))
                             : loadScene(resolveScenePath(c.scene), {{"/camera/width", 240}, {"/camera/height", 135}});
    if (c.addLights) {
      Light spot;
      spot.name = "spot";
      spot.type = LightType::Spot;
      spot.position = {0.5f, 6.0f, 0.3f};
      spot.direction = glm::normalize(glm::vec3(-0.1f, -1.0f, -0.05f));
      spot.coneDeg = 50.0f;
      Light point;
      point.name = "point";
      point.type = LightType::Point;
      point.position = {3.0f, 4.0f, 2.0f};
      scene.lights.push_back(spot);
      scene.lights.push_back(point);
    }
    ReferenceOptions options;
    options.spp = c.spp;
    options.threads = 2;
    options.channels = ReferenceChannels::All;
    options.simd = ReferenceSimd::Baseline;
    ReferenceStats baselineStats, avx2Stats;
    std::vector<uint8_t> baselinePicture, avx2Picture;
    const Frame baseline = renderReference(scene, options, &baselineStats, &baselinePicture);
    options.simd = ReferenceSimd::Avx2;
    const Frame avx2 = renderReference(scene, options, &avx2Stats, &avx2Picture);
    ASSERT_EQ(avx2.names, baseline.names);
    for (size_t k = 0; k < baseline.names.size(); ++k) {
      ASSERT_EQ(avx2.data[k].size(), baseline.data[k].size());
      EXPECT_EQ(std::memcmp(avx2.data[k].data(), baseline.data[k].data(), baseline.data[k].size() * sizeof(float)), 0)
          << "channel " << baseline.names[k];
    }
    EXPECT_EQ(avx2Picture, baselinePicture);
    EXPECT_EQ(avx2Stats.primaryRays, baselineStats.primaryRays);
    EXPECT_EQ(avx2Stats.shadowRays, baselineStats.shadowRays);
    EXPECT_GT(baselineStats.shadowRays, 0u);
    if (c.addLights) {
      const auto& hit = baseline.get("hit");
      const auto& spotVis = baseline.get("light.spot.vis");
      const auto& pointVis = baseline.get("light.point.vis");
      for (size_t i = 0; i < hit.size(); ++i) {
        if (hit[i] != 1.0f) continue;
        spotLit += spotVis[i] == 1.0f;
        spotDark += spotVis[i] == 0.0f;
        pointLit += pointVis[i] == 1.0f;
        pointDark += pointVis[i] == 0.0f;
      }
    }
  }
  // Not vacuous: the added lights light some surfaces and leave others dark.
  EXPECT_GT(spotLit, 0u);
  EXPECT_GT(spotDark, 0u);
  EXPECT_GT(pointLit, 0u);
  EXPECT_GT(pointDark, 0u);
}

// The light channels agree with each other and with N on every bundled scene (All set, spp 1, each
// scene's directional lights): a hit pixel whose N faces away from the light (dot(N, toLight) <= 0,
// the trace's own facing test) has vis 0 and occluder_dist exactly 0; one facing it is lit with
// occluder_dist -1 or dark with occluder_dist > 0. The frame's planes are filled with -1
// (occluder_dist) and 0 before the trace, and a tile row equal to the fill is not written: a row
// skipped when it should have been written (a wrong fill value) leaves -1 where 0 belongs.
TEST(ReferenceRobustness, LightChannelsAgreeWithTheNormalOnEveryBundledScene) {
  size_t facingAway = 0, lit = 0, shadowed = 0;
  for (const std::string& name : bundledSceneNames()) {
    SCOPED_TRACE(name);
    const Scene scene = loadScene(resolveScenePath(name));
    ReferenceOptions options;
    options.channels = ReferenceChannels::All;
    const Frame frame = renderReference(scene, options);
    const auto& hit = frame.get("hit");
    const float* n[3] = {frame.get("N.x").data(), frame.get("N.y").data(), frame.get("N.z").data()};
    for (const Light& light : scene.lights) {
      if (light.type != LightType::Directional) continue;
      const glm::vec3 toLight = glm::normalize(-light.direction);
      const auto& vis = frame.get("light." + light.name + ".vis");
      const auto& dist = frame.get("light." + light.name + ".occluder_dist");
      size_t wrong = 0;
      std::string first;
      for (size_t i = 0; i < hit.size(); ++i) {
        if (hit[i] != 1.0f) continue;
        const bool facing = glm::dot(glm::vec3(n[0][i], n[1][i], n[2][i]), toLight) > 0.0f;
        bool ok;
        if (!facing) {
          ok = vis[i] == 0.0f && dist[i] == 0.0f && !std::signbit(dist[i]);
          ++facingAway;
        } else if (vis[i] == 1.0f) {
          ok = dist[i] == -1.0f;
          ++lit;
        } else {
          ok = vis[i] == 0.0f && dist[i] > 0.0f;
          ++shadowed;
        }
        if (!ok && wrong++ == 0)
          first = "pixel " + std::to_string(i) + ": facing " + std::to_string(facing) + ", vis " +
                  std::to_string(vis[i]) + ", occluder_dist " + std::to_string(dist[i]);
      }
      EXPECT_EQ(wrong, 0u) << light.name << ": " << first;
    }
  }
  EXPECT_GT(facingAway, 1000u);
  EXPECT_GT(lit, 100000u);
  EXPECT_GT(shadowed, 10000u);
}

// The picture renderReference draws during the trace (what `shadowlab reference` writes, from a
// Compare trace) is referencePicture's, byte for byte, drawn from the All frame: with a projector,
// at spp 4 (averaged visibility and colours), on a mesh, and without any light.
TEST(ReferenceRobustness, PictureDrawnDuringTheTraceEqualsReferencePicture) {
  struct Case {
    const char* scene;
    int spp;
    bool dropLights;
  };
  for (const Case& c : {Case{"projector", 1, false}, Case{"alpha_fence", 4, false}, Case{"bunny", 1, false},
                        Case{"projector", 1, true}}) {
    SCOPED_TRACE(std::string(c.scene) + " spp " + std::to_string(c.spp) + (c.dropLights ? " without lights" : ""));
    Scene scene = loadScene(resolveScenePath(c.scene), {{"/camera/width", 320}, {"/camera/height", 180}});
    if (c.dropLights) scene.lights.clear();
    ReferenceOptions options;
    options.spp = c.spp;
    options.channels = ReferenceChannels::All;
    const std::vector<uint8_t> expected = referencePicture(scene, renderReference(scene, options));
    options.channels = ReferenceChannels::Compare;
    std::vector<uint8_t> picture;
    const Frame compareSet = renderReference(scene, options, nullptr, &picture);
    EXPECT_FALSE(compareSet.has("N.x"));
    ASSERT_EQ(picture.size(), size_t(320 * 180 * 3));
    EXPECT_EQ(picture, expected);
    // Not blank: something lit, something dark.
    EXPECT_NE(*std::max_element(picture.begin(), picture.end()), *std::min_element(picture.begin(), picture.end()));
  }
  const Scene scene = loadScene(resolveScenePath("projector"), {{"/camera/width", 64}, {"/camera/height", 36}});
  EXPECT_EQ(referenceFrameBytes(scene, ReferenceChannels::Compare), 8.0 * 64 * 36 * 4);
  EXPECT_EQ(referenceFrameBytes(scene, ReferenceChannels::All), 17.0 * 64 * 36 * 4);
}

// The metadata and channel names exactly as scenes/frame.h documents them, and the hashes:
// referenceHash changes with spp and camera but not with the thread count.
TEST(ReferenceRobustness, ChannelsMetadataAndHashes) {
  const Scene scene = loadScene(resolveScenePath("projector"), {{"/camera/width", 64}, {"/camera/height", 36}});
  ReferenceStats stats;
  const Frame frame = renderReference(scene, {}, &stats);
  const std::vector<std::string> expected = {"hit",
                                             "object_id",
                                             "prim_id",
                                             "P.x",
                                             "P.y",
                                             "P.z",
                                             "N.x",
                                             "N.y",
                                             "N.z",
                                             "light.sun.vis",
                                             "light.sun.occluder_dist",
                                             "proj.slide.coverage",
                                             "proj.slide.u",
                                             "proj.slide.v",
                                             "proj.slide.R",
                                             "proj.slide.G",
                                             "proj.slide.B"};
  EXPECT_EQ(frame.names, expected);
  EXPECT_EQ(frame.meta["kind"], "reference");
  EXPECT_EQ(frame.meta["scene"], "projector");
  EXPECT_EQ(frame.meta["scene_hash"], scene.hash);
  EXPECT_EQ(frame.meta["width"], 64);
  EXPECT_EQ(frame.meta["height"], 36);
  EXPECT_EQ(frame.meta["lights"], nlohmann::json::array({"sun"}));
  EXPECT_EQ(frame.meta["projectors"], nlohmann::json::array({"slide"}));
  EXPECT_EQ(frame.meta["camera_hash"].get<std::string>().size(), 16u);
  EXPECT_EQ(stats.primaryRays, 64u * 36u);
  EXPECT_GT(stats.shadowRays, 0u);

  ReferenceOptions options;
  const std::string base = referenceHash(scene, options);
  // The key's text (reference/README.md): version /2 since the cache holds the Compare set.
  const std::string key = "shadowlab.reference/2;scene=" + scene.hash + ";camera=" + scene.camera.hash() + ";spp=1";
  EXPECT_EQ(base, hashHex(fnv1a64(key.data(), key.size())));
  options.threads = 3;
  EXPECT_EQ(referenceHash(scene, options), base);
  options.channels = ReferenceChannels::Compare;  // the same values: the same key
  EXPECT_EQ(referenceHash(scene, options), base);
  options.spp = 4;
  EXPECT_NE(referenceHash(scene, options), base);
  Scene moved = scene;
  moved.camera.position.x += 0.001f;
  EXPECT_NE(referenceHash(moved, {}), base);

  // N faces the camera and is unit length wherever there is a hit; misses are all zero.
  const auto& hit = frame.get("hit");
  for (size_t i = 0; i < frame.pixelCount(); ++i) {
    const glm::vec3 n(frame.get("N.x")[i], frame.get("N.y")[i], frame.get("N.z")[i]);
    const glm::vec3 p(frame.get("P.x")[i], frame.get("P.y")[i], frame.get("P.z")[i]);
    if (hit[i] == 1.0f) {
      EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
      EXPECT_LT(glm::dot(n, p - scene.camera.position), 0.0f);
    } else {
      EXPECT_EQ(frame.get("object_id")[i], 0.0f);
      EXPECT_EQ(glm::length(n), 0.0f);
      EXPECT_EQ(frame.get("light.sun.vis")[i], 0.0f);
    }
  }
  // The readable picture has one RGB triple per pixel and is not blank.
  const std::vector<uint8_t> picture = referencePicture(scene, frame);
  ASSERT_EQ(picture.size(), frame.pixelCount() * 3);
  EXPECT_NE(*std::max_element(picture.begin(), picture.end()), *std::min_element(picture.begin(), picture.end()));
}

// A scene where every camera ray misses: a light and a projector, no geometry (objects added by
// the caller), and the check that every channel of its frame holds its "no hit" value.
Scene missScene(const std::string& name, int width, int height) {
  Scene scene;
  scene.name = name;
  scene.hash = "0000000000000000";
  scene.camera.width = width;
  scene.camera.height = height;
  scene.materials.push_back(Material{});
  Light sun;
  sun.name = "sun";
  scene.lights.push_back(sun);
  Projector projector;
  projector.name = "slide";
  scene.projectors.push_back(projector);
  return scene;
}

void expectAllMisses(const Scene& scene, const ReferenceOptions& options) {
  ReferenceStats stats;
  const Frame frame = renderReference(scene, options, &stats);
  EXPECT_EQ(stats.primaryRays, uint64_t(scene.camera.width) * uint64_t(scene.camera.height));
  EXPECT_EQ(stats.shadowRays, 0u);
  ASSERT_EQ(frame.names, referenceChannelNames(scene, options.channels));
  for (size_t c = 0; c < frame.names.size(); ++c) {
    const float expected = frame.names[c] == "light.sun.occluder_dist" ? -1.0f : 0.0f;
    for (float value : frame.data[c]) ASSERT_EQ(value, expected) << frame.names[c];
  }
}

// Degenerate but legal inputs: an object with no triangles, a light and a projector: everything
// misses, nothing throws, every channel holds its "no hit" value.
TEST(ReferenceRobustness, EmptySceneRendersAllMisses) {
  Scene scene = missScene("empty", 40, 30);
  Object nothing;
  nothing.name = "nothing";
  nothing.id = 7;
  scene.objects.push_back(nothing);
  expectAllMisses(scene, {});
}

// No object at all (a library caller's scene; the loader never makes one): the packet code reads
// per-geometry tables only for lanes that hit, so there is nothing to read past; every pixel a miss,
// with the light's and the projector's channels at their no-hit values, with the Compare and the
// All set.
TEST(ReferenceRobustness, SceneWithoutObjectsRendersAllMisses) {
  const Scene scene = missScene("nothing", 24, 10);
  for (ReferenceChannels channels : {ReferenceChannels::Compare, ReferenceChannels::All}) {
    ReferenceOptions options;
    options.channels = channels;
    options.spp = 4;
    expectAllMisses(scene, options);
  }
}

// Inconsistent meshes are reported, never traced into a crash: an index past the positions or a
// missing per-triangle material is an internal error (the loader never makes one), an
// alpha-tested material on an object without texture coordinates is bad input.
TEST(ReferenceRobustness, RejectsInconsistentMeshes) {
  auto base = [] {
    Scene scene;
    scene.name = "broken";
    scene.path = "broken.json";
    scene.camera.width = 8;
    scene.camera.height = 8;
    scene.materials.push_back(Material{});
    Object tri;
    tri.name = "tri";
    tri.id = 1;
    tri.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    tri.triangles = {{0, 1, 2}};
    tri.triangleMaterial = {0};
    scene.objects.push_back(tri);
    return scene;
  };
  EXPECT_NO_THROW(renderReference(base(), {}));
  Scene pastEnd = base();
  pastEnd.objects[0].triangles[0].z = 3;
  EXPECT_THROW(renderReference(pastEnd, {}), DriverError);
  Scene noMaterial = base();
  noMaterial.objects[0].triangleMaterial.clear();
  EXPECT_THROW(renderReference(noMaterial, {}), DriverError);
  Scene badMaterial = base();
  badMaterial.objects[0].triangleMaterial[0] = 5;
  EXPECT_THROW(renderReference(badMaterial, {}), DriverError);
  Scene alphaWithoutUv = base();
  alphaWithoutUv.materials[0].hasAlpha = true;
  alphaWithoutUv.materials[0].alphaTexture = Image{1, 1, 1, {1.0f}};
  try {
    renderReference(alphaWithoutUv, {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("broken.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("\"tri\""), std::string::npos) << e.what();
  }
}

TEST(ReferenceRobustness, RejectsBadOptions) {
  const Scene scene = loadScene(resolveScenePath("contact"), {{"/camera/width", 32}, {"/camera/height", 18}});
  for (int spp : {0, -1, 1025}) {
    ReferenceOptions options;
    options.spp = spp;
    EXPECT_THROW(renderReference(scene, options), InputError) << spp;
  }
  ReferenceOptions options;
  options.threads = -2;
  EXPECT_THROW(renderReference(scene, options), InputError);
}

}  // namespace

}  // namespace reference_robustness_test
