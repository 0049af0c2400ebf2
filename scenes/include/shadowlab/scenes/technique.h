#pragma once
// A technique file (method key `technique`, raster/METHODS.md "Your own technique"): GLSL that
// defines `float shadowVisibility(ShadowQuery q)`, the visibility of one pixel in [0, 1], and
// declares its own method keys in header lines
//   // shadowlab: key radius float 1.5 range 0.25..8
// (`technique.radius` in method files, --set, --grid, tune), and may ask for a filterable map's
// moments with a header line
//   // shadowlab: moments vsm
// (vsm, evsm2, evsm4 or msm: the harness renders and blurs that filter's moments and offers them as
// `mapMoments` and ShadowQuery::moments). This part reads and checks the text
// without a GPU: UTF-8, no #include, the function's signature, the declarations, the content hash.
// raster/ compiles it (raster/src/technique_compiler.cpp).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace shadowlab {

struct TechniqueParam {
  enum class Type { Float, Int, Bool };
  std::string name;  // the key's part after "technique.", a GLSL identifier
  Type type = Type::Float;
  double defaultValue = 0;
  double lo = 0, hi = 0;  // inclusive; bool: 0..1; without a range: -1e30..1e30
  int line = 0;           // 1-based line of the declaration
};

struct TechniqueFile {
  std::string path;                    // as the method named it
  std::string source;                  // the file's bytes (checked UTF-8)
  std::string stem;                    // file name without folder and extension: "pcf" for examples/techniques/pcf.glsl
  std::string hash;                    // 16 hex digits, FNV-1a 64 of the bytes
  std::vector<TechniqueParam> params;  // in declaration order
  // "// shadowlab: moments <filter>": the filterable map's key (vsm, evsm2, evsm4, msm) whose moments
  // the harness renders for the file; empty: none (the file may not read them).
  std::string moments;
  int momentsLine = 0;  // 1-based line of that declaration
  // The code names ShadowQuery::planeSlope (or pastes tokens, ##): its lookup needs the normal.
  bool readsPlaneSlope = false;
  // "pcf@0123456789abcdef": how results name the technique (method key technique.hash).
  std::string id() const { return stem + "@" + hash; }
  const TechniqueParam* find(const std::string& name) const;
};

// The largest technique file read (bytes): glslang's compile time and memory grow with the text,
// and a lookup function is a few KiB.
constexpr size_t kTechniqueMaxBytes = 256 * 1024;

// The name of the function a technique file defines, and its signature as errors print it.
constexpr const char* kTechniqueFunction = "shadowVisibility";
constexpr const char* kTechniqueSignature = "float shadowVisibility(ShadowQuery q)";

// Reads and checks `path`: throws InputError "path:line:column: error: ..." for a file that is
// missing, not UTF-8 text, has an #include, a malformed or duplicate declaration, a default
// outside its range, reads the moments (mapMoments, ShadowQuery::moments) without a moments line, or no `float
// shadowVisibility(ShadowQuery q)` (misspelled names and wrong signatures named at their line). Parsed once per content
// (a cache keyed by path and bytes).
const TechniqueFile& loadTechniqueFile(const std::string& path);

// A parameter's value as the method's JSON prints it (int, bool or float) and as the shader's
// specialization constant holds it (the 32-bit pattern of an int, a bool or a float).
uint32_t techniqueParamBits(const TechniqueParam& p, double value);

}  // namespace shadowlab
