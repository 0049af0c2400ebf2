// image_io.h through OpenImageIO loaded on first use (SHADOWLAB_IMAGE_IO=oiio with
// SHADOWLAB_IMAGE_IO_MODULE=ON, the default; scenes/CMakeLists.txt). OpenImageIO brings ~260 shared
// libraries (GDAL, ffmpeg, OpenCV, ...); linked into the program, the dynamic loader resolves all of
// them before main(), ~0.2 s of every command's start on the 2-core machine, even for commands that
// never touch an image (gate, version, scenes). As a module (libshadowlab_image_io_oiio.so, next to
// the shadowlab binary), they load when the first image is read or written, or earlier on a thread
// of its own where a command asks for that (preload: the sweep runner, before its device starts).
// The module is looked for in $SHADOWLAB_IMAGE_IO_MODULE (when set), next to the running program,
// then where the build put it. When it cannot be loaded every function returns why (the callers add
// the file's path), so a command that needs no image still runs.
// With SHADOWLAB_IMAGE_IO_HYBRID (OpenEXR and libpng found: the default) EXR and PNG files go through
// image_io_exr_png.cpp, linked in: the reference cache, frames, triptychs, PNG textures never load
// the module, which then serves textures in other formats only (image_io.h). Loading it takes
// ~0.2 s and holds the dynamic loader's lock, so the sweep's device (lavapipe, LLVM) would wait for
// it: a two-row sweep takes ~0.3 s longer with it.
#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "image_io_table.h"

namespace shadowlab::image_io {
namespace {

constexpr const char* kModuleName = "libshadowlab_image_io_oiio.so";

std::string programDir() {
  std::vector<char> buf(4096);
  const ssize_t n = ::readlink("/proc/self/exe", buf.data(), buf.size() - 1);
  if (n <= 0) return "";
  std::string exe(buf.data(), size_t(n));
  const size_t slash = exe.rfind('/');
  return slash == std::string::npos ? "" : exe.substr(0, slash);
}

struct Module {
  const Table* table = nullptr;
  std::string error;  // why there is no table
};

Module load() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("SHADOWLAB_IMAGE_IO_MODULE"); env && *env) {
    candidates.push_back(env);  // set: the only place looked at
  } else {
    if (const std::string dir = programDir(); !dir.empty()) candidates.push_back(dir + "/" + kModuleName);
    candidates.push_back(SHADOWLAB_IMAGE_IO_MODULE_FILE);
  }
  Module m;
  std::string tried;
  auto refused = [&tried](const std::string& path, const std::string& why) {
    tried += (tried.empty() ? "" : ", ") + path + " (" + why + ")";
  };
  for (const std::string& path : candidates) {
    if (::access(path.c_str(), F_OK) != 0) {
      refused(path, "missing");
      continue;
    }
    void* handle = ::dlopen(path.c_str(), RTLD_LAZY | RTLD_LOCAL | RTLD_NODELETE);
    if (!handle) {
      const char* why = ::dlerror();
      refused(path, why ? why : "dlopen failed");
      continue;
    }
    using Entry = const Table* (*)();
    auto entry = reinterpret_cast<Entry>(::dlsym(handle, "shadowlab_image_io_table"));
    const Table* table = entry ? entry() : nullptr;
    if (!table || table->version != kTableVersion) {
      refused(path, "not this build's image module");
      continue;
    }
    m.table = table;
    return m;
  }
  m.error = "cannot load OpenImageIO's module " + std::string(kModuleName) + ": tried " + tried +
            " (set SHADOWLAB_IMAGE_IO_MODULE to its path)";
  return m;
}

const Module& module() {
  static const Module m = load();  // once, thread-safe
  return m;
}

}  // namespace

#ifdef SHADOWLAB_IMAGE_IO_HYBRID

std::string writeExr(const std::string& path, const FloatImage& image) { return exr_png::writeExr(path, image); }

std::string readExr(const std::string& path, FloatImage& image) { return exr_png::readExr(path, image); }

std::string writePng(const std::string& path, int width, int height, int channels, const uint8_t* pixels,
                     bool unfiltered) {
  return exr_png::writePng(path, width, height, channels, pixels, unfiltered);
}

// .png and .exr as the exr-png build reads them; any other name through OpenImageIO.
std::string readTexture(const std::string& path, FloatImage& image, int maxSide) {
  if (exr_png::readsTexture(path)) return exr_png::readTexture(path, image, maxSide);
  const Module& m = module();
  return m.table ? m.table->readTexture(path, image, maxSide) : m.error;
}

const char* backendName() { return "exr-png+oiio"; }

// Nothing to load ahead: EXR and PNG need no module, and a texture that needs it is read while the
// scene loads, before anything a preload could overlap.
void preload() {}

#else

std::string writeExr(const std::string& path, const FloatImage& image) {
  const Module& m = module();
  return m.table ? m.table->writeExr(path, image) : m.error;
}

std::string readExr(const std::string& path, FloatImage& image) {
  const Module& m = module();
  return m.table ? m.table->readExr(path, image) : m.error;
}

std::string writePng(const std::string& path, int width, int height, int channels, const uint8_t* pixels,
                     bool unfiltered) {
  const Module& m = module();
  return m.table ? m.table->writePng(path, width, height, channels, pixels, unfiltered) : m.error;
}

std::string readTexture(const std::string& path, FloatImage& image, int maxSide) {
  const Module& m = module();
  return m.table ? m.table->readTexture(path, image, maxSide) : m.error;
}

const char* backendName() { return "oiio"; }

void preload() {
  // Joined when the program exits (a static's destructor), so exit never races a half-done load.
  struct Loader {
    std::thread thread{[] { module(); }};
    ~Loader() { thread.join(); }
  };
  static Loader loader;
}

#endif

}  // namespace shadowlab::image_io
