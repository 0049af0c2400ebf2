// Scene loading cost: every renderer run pays it once per scene (and sweeps once per variant).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <benchmark/benchmark.h>

#include "../tests/support/gltf_builder.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/loader.h"

namespace {

void BM_LoadScene(benchmark::State& state, const char* name) {
  std::string path = shadowlab::resolveScenePath(name);
  size_t triangles = 0;
  for (auto _ : state) {
    shadowlab::Scene s = shadowlab::loadScene(path);
    triangles = s.triangleCount();
    benchmark::DoNotOptimize(s.hash);
  }
  state.counters["triangles"] = double(triangles);
  state.counters["Mtris/s"] =
      benchmark::Counter(double(triangles) * state.iterations() / 1e6, benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_LoadScene, sphere_on_plane, "sphere_on_plane")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadScene, bunny, "bunny")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadScene, long_view, "long_view")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadScene, projector, "projector")->Unit(benchmark::kMillisecond);

// The same 2-million-triangle mesh (a 1001 x 1001 height field: 1,002,001 vertices, 2,000,000
// triangles sharing them, pseudo-random float heights) as OBJ and as .glb, each inside the same
// JSON scene, loaded side by side: the glTF loader must never be the slower way in.
const std::string& bigMeshDir() {
  static const std::string dir = [] {
    const std::string d = (std::filesystem::temp_directory_path() / "shadowlab_scenes_bench_2m").string();
    std::filesystem::create_directories(d);
    const int n = 1001;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> h(0.0f, 0.05f);
    std::vector<glm::vec3> v;
    v.reserve(size_t(n) * n);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) v.emplace_back(float(i) / (n - 1) * 10 - 5, 1 + h(rng), float(j) / (n - 1) * 10 - 5);
    std::vector<uint32_t> idx;
    idx.reserve(size_t(n - 1) * (n - 1) * 6);
    for (int j = 0; j + 1 < n; ++j)
      for (int i = 0; i + 1 < n; ++i) {
        const uint32_t a = uint32_t(j * n + i), b = a + 1, c = a + uint32_t(n), e = c + 1;
        idx.insert(idx.end(), {a, c, b, b, c, e});
      }
    {
      std::FILE* f = std::fopen((d + "/mesh.obj").c_str(), "w");
      for (const auto& p : v) std::fprintf(f, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
      for (size_t t = 0; t < idx.size(); t += 3)
        std::fprintf(f, "f %u %u %u\n", idx[t] + 1, idx[t + 1] + 1, idx[t + 2] + 1);
      std::fclose(f);
    }
    shadowlab::testing::GltfBuilder g;
    g.doc["materials"] = {{{"doubleSided", true}}};
    g.mesh(g.positions(v), g.indices32(idx), -1, 0);
    g.node({{"mesh", 0}});
    g.scene({0});
    g.write(d, "mesh", shadowlab::testing::GltfBuilder::Form::Binary);
    for (const char* kind : {"obj", "glb"}) {
      std::ofstream(d + "/" + kind + ".json")
          << R"({"camera": {"position": [0, 8, 12], "look_at": [0, 0, 0], "vfov_deg": 45, "width": 640, "height": 360},
                 "objects": [{"type": ")"
          << (std::string(kind) == "obj" ? "obj" : "gltf") << R"(", "name": "mesh", "path": "mesh.)" << kind
          << R"("}], "lights": [{"type": "directional", "elevation_deg": 50}]})";
    }
    return d;
  }();
  return dir;
}

void BM_Load2MTriangles(benchmark::State& state, const char* kind) {
  const std::string path = bigMeshDir() + "/" + kind + ".json";
  size_t triangles = 0;
  for (auto _ : state) {
    shadowlab::Scene s = shadowlab::loadScene(path);
    triangles = s.triangleCount();
    benchmark::DoNotOptimize(s.hash);
  }
  state.counters["triangles"] = double(triangles);
  state.counters["Mtris/s"] =
      benchmark::Counter(double(triangles) * state.iterations() / 1e6, benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_Load2MTriangles, obj, "obj")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Load2MTriangles, glb, "glb")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_LoadScene, gltf_cards, "gltf_cards")->Unit(benchmark::kMillisecond);

// A reference-sized frame (1080p, 12 channels) through EXR: the compare step reads these.
void BM_FrameExrRoundTrip(benchmark::State& state) {
  shadowlab::Frame f;
  f.width = 1920;
  f.height = 1080;
  for (const char* n : {"hit", "object_id", "prim_id", "P.x", "P.y", "P.z", "N.x", "N.y", "N.z", "light.sun.vis",
                        "light.sun.occluder_dist", "proj.p.coverage"}) {
    auto& plane = f.add(n);
    for (size_t i = 0; i < plane.size(); ++i) plane[i] = float(i % 977) * 0.25f;
  }
  std::string path = "/tmp/shadowlab_scenes_bench_frame.exr";
  for (auto _ : state) {
    shadowlab::writeFrameExr(f, path);
    shadowlab::Frame g = shadowlab::readFrameExr(path);
    benchmark::DoNotOptimize(g.data);
  }
}
BENCHMARK(BM_FrameExrRoundTrip)->Unit(benchmark::kMillisecond);

// The read alone of a reference cache entry (what a sweep's first row waits for): the file named by
// $SHADOWLAB_BENCH_EXR, else a 1080p frame of the Compare set's shape (hit, ids, vis, occluder
// distance: flat regions and a few edges, as a traced frame has).
void BM_ReadReferenceExr(benchmark::State& state) {
  std::string path;
  if (const char* env = std::getenv("SHADOWLAB_BENCH_EXR"); env && *env) {
    path = env;
  } else {
    shadowlab::Frame f;
    f.width = 1920;
    f.height = 1080;
    const int w = f.width;
    auto fill = [&](const char* name, auto value) {
      auto& plane = f.add(name);
      for (size_t i = 0; i < plane.size(); ++i) plane[i] = value(int(i % size_t(w)), int(i / size_t(w)));
    };
    auto inSphere = [](int x, int y) { return (x - 960) * (x - 960) + (y - 500) * (y - 500) < 300 * 300; };
    fill("hit", [](int, int y) { return y > 200 ? 1.0f : 0.0f; });
    fill("object_id", [&](int x, int y) { return y <= 200 ? 0.0f : inSphere(x, y) ? 2.0f : 1.0f; });
    fill("prim_id", [&](int x, int y) { return y <= 200 ? 0.0f : float((x / 37) * 31 + y / 41); });
    fill("light.sun.vis", [&](int x, int y) { return inSphere(x + 250, y - 150) && !inSphere(x, y) ? 0.0f : 1.0f; });
    fill("light.sun.occluder_dist",
         [&](int x, int y) { return inSphere(x + 250, y - 150) && !inSphere(x, y) ? 0.5f + float(x % 300) * 1e-3f : -1.0f; });
    path = "/tmp/shadowlab_scenes_bench_reference.exr";
    shadowlab::writeFrameExr(f, path);
  }
  for (auto _ : state) {
    shadowlab::Frame g = shadowlab::readFrameExr(path);
    benchmark::DoNotOptimize(g.data);
  }
}
BENCHMARK(BM_ReadReferenceExr)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
