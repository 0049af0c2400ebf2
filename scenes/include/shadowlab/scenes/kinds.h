#ifndef SHADOWLAB_SCENES_KINDS_H
#define SHADOWLAB_SCENES_KINDS_H
// The kinds a method or scene file names by key, each defined once, as one X-macro row:
//   X(Enumerator, code, "key", "help")
// C++ builds from these rows the enum (method.h, scene.h), the key <-> enum tables that parse,
// print and list the choices in error messages ("expected one of ..."); GLSL (resolve.frag, via
// raster/shaders/resolve_abi.h) builds its `kFilter<Enumerator>` / `kLight<Enumerator>` constants
// from the same rows, so the shader's switch codes cannot drift from the C++ enum.
// This file is read by C++ and by glslang (GL_GOOGLE_include_directive): only the preprocessor
// features both share (no #pragma once, no C++ in the rows).
//
// A new kind is a new row here plus the code that is truly new (its shader branch, its fit);
// raster/METHODS.md documents it.

// filter: how the map comparisons around the lookup are combined into light.L.vis.
#define SHADOWLAB_FILTERS(X)                                                                             \
  X(None, 0, "none", "the texel under the lookup, one comparison")                                       \
  X(Hw2x2, 1, "hw2x2", "the sampler's 2x2 comparisons, blended bilinearly by the hardware")              \
  X(Bilinear4, 2, "bilinear4", "2x2 comparisons blended bilinearly in the shader")                       \
  X(Pcf, 3, "pcf", "the mean of filter.size x filter.size comparisons around the lookup texel")          \
  X(Poisson, 4, "poisson", "the mean of filter.taps comparisons on a disc of filter.radius texels")      \
  X(Vsm, 5, "vsm", "variance shadow map: Chebyshev's bound from 2 blurred moments (vsm.*, filter.blur)") \
  X(Evsm2, 6, "evsm2", "exponential VSM, the positive warp's 2 moments (evsm.exponent_pos, vsm.*)")      \
  X(Evsm4, 7, "evsm4", "exponential VSM, positive and negative warps, 4 moments (evsm.*, vsm.*)")        \
  X(Msm, 8, "msm", "moment shadow map: Hamburger 4-moment bound (msm.moment_bias, filter.blur)")         \
  X(Pcss, 9, "pcss", "soft: blocker search, penumbra from the light size, PCF over it (pcss.*)")         \
  X(Dpcf, 10, "dpcf", "soft: one kernel hardened towards contact (Filament's DPCF; dpcf.*)")

// fit: how a directional light's orthographic map is fitted (spot and point lights ignore it).
#define SHADOWLAB_FITS(X)                                                                        \
  X(Sphere, 0, "sphere", "the scene's bounding sphere")                                          \
  X(Tight, 1, "tight", "the fit camera's view frustum intersected with the scene")               \
  X(Cascades, 2, "cascades", "one tight crop per slice of the view depth (cascades.*)")          \
  X(Lispsm, 3, "lispsm", "the tight body under a light-space perspective warp (lispsm.n_scale)") \
  X(Psm, 4, "psm", "perspective shadow map: the map in the camera's post-perspective space (psm.slide_back)") \
  X(Tsm, 5, "tsm", "the view frustum's trapezoid warped onto the map (tsm.focus, tsm.focus_distance)") \
  X(Sdsm, 6, "sdsm", "cascades over the visible samples' depth range, each cropped to its samples (cascades.*, sdsm.snap)")

// A scene light's "type".
#define SHADOWLAB_LIGHT_TYPES(X)                                                  \
  X(Directional, 0, "directional", "parallel rays along direction, one 2D map")   \
  X(Spot, 1, "spot", "a cone from position along direction, one perspective map") \
  X(Point, 2, "point", "all directions from position, a cube map of six faces")

#ifdef __cplusplus
#include <string>
#include <vector>

namespace shadowlab {

// An enumerator of a row (method.h, scene.h build their enums with it: the codes are the rows').
#define SHADOWLAB_ENUMERATOR(name, code, key, help) name = code,

// One row, as C++ iterates it.
template <class E>
struct KindInfo {
  E kind;
  const char* key;   // as the files, --set and --grid spell it
  const char* help;  // one line, for listings
};

// "a, b, c": a table's keys, for "expected one of ..." messages.
template <class E>
std::string kindKeys(const std::vector<KindInfo<E>>& kinds) {
  std::string s;
  for (const KindInfo<E>& k : kinds) s += (s.empty() ? "" : ", ") + std::string(k.key);
  return s;
}

// The row of `key`, or nullptr.
template <class E>
const KindInfo<E>* findKind(const std::vector<KindInfo<E>>& kinds, const std::string& key) {
  for (const KindInfo<E>& k : kinds)
    if (key == k.key) return &k;
  return nullptr;
}

// The key of `kind` ("?" for a value outside the table).
template <class E>
const char* kindKey(const std::vector<KindInfo<E>>& kinds, E kind) {
  for (const KindInfo<E>& k : kinds)
    if (k.kind == kind) return k.key;
  return "?";
}

}  // namespace shadowlab
#endif

#endif
