// The value rules of a frame read from a file (frame_check.h): one rule per channel, chosen by its
// name, and one pass over each plane.
#include "shadowlab/compare/frame_check.h"

#include <limits>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/number_text.h"

namespace shadowlab {
namespace {

constexpr float kMaxFloat = std::numeric_limits<float>::max();
// Ids are stored as floats: exact up to 2^24 (frame.h).
constexpr float kMaxId = 16777216.0f;

struct Rule {
  float lo = -kMaxFloat;
  float hi = kMaxFloat;
  bool integer = false;
  bool minusOne = false;  // -1 is allowed besides [lo, hi] (occluder_dist's "unoccluded")
  const char* expected = "a finite number";
};

bool endsWith(const std::string& s, const char* suffix) {
  const std::string t(suffix);
  return s.size() >= t.size() && s.compare(s.size() - t.size(), t.size(), t) == 0;
}

// The channel's rule from its name: the contract's channels (frame.h) by their exact name or, for a
// light's or projector's, the last component after "light.L." / "proj.P.".
Rule ruleFor(const std::string& name) {
  const Rule unit{0.0f, 1.0f, false, false, "a number in [0, 1]"};
  const Rule id{0.0f, kMaxId, true, false, "an integer in [0, 16777216]"};
  const Rule nonNegative{0.0f, kMaxFloat, false, false, "a finite number >= 0"};
  if (name == "hit") return unit;
  if (name == "object_id" || name == "prim_id") return id;
  const bool light = name.rfind("light.", 0) == 0, projector = name.rfind("proj.", 0) == 0;
  if (light) {
    if (endsWith(name, ".vis") || endsWith(name, ".in_map") || endsWith(name, ".vis_sigma")) return unit;
    if (endsWith(name, ".occluder_id") || endsWith(name, ".occluder_prim") || endsWith(name, ".cascade")) return id;
    if (endsWith(name, ".occluder_dist"))
      return Rule{0.0f, kMaxFloat, false, true, "-1 (unoccluded) or a finite number >= 0"};
    if (endsWith(name, ".m")) return nonNegative;
  }
  if (projector) {
    if (endsWith(name, ".coverage") || endsWith(name, ".reverse")) return unit;
    if (endsWith(name, ".R") || endsWith(name, ".G") || endsWith(name, ".B")) return nonNegative;
  }
  return Rule{};
}

}  // namespace

void checkFrameValues(const Frame& frame, const std::string& file) {
  const size_t pixels = frame.pixelCount();
  for (size_t c = 0; c < frame.names.size() && c < frame.data.size(); ++c) {
    const std::vector<float>& plane = frame.data[c];
    const Rule rule = ruleFor(frame.names[c]);
    // A comparison that NaN fails, so that NaN is out of every range; the common case is one
    // branch-free test per value and no bookkeeping.
    auto bad = [&](float v) {
      const bool inRange = (v >= rule.lo && v <= rule.hi) || (rule.minusOne && v == -1.0f);
      return !inRange || (rule.integer && v != float(int64_t(v)));
    };
    size_t first = pixels, count = 0;
    const size_t n = std::min(plane.size(), pixels);
    for (size_t i = 0; i < n; ++i) {
      if (bad(plane[i])) {
        if (count++ == 0) first = i;
      }
    }
    if (count == 0) continue;
    const int x = int(first % size_t(frame.width)), y = int(first / size_t(frame.width));
    throw InputError(formatError(file, frame.names[c] + " pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")",
                                 "got " + numberText(plane[first]) + "; expected " + rule.expected + " (first of " +
                                     std::to_string(count) + (count == 1 ? " such pixel)" : " such pixels)")));
  }
}

Frame readFrameToCompare(const std::string& path) {
  Frame frame = readFrameExr(path);
  checkFrameValues(frame, path);
  return frame;
}

}  // namespace shadowlab
