// tinygltf's implementation (Debian's libtinygltf-dev header), compiled here rather than linked from
// its shared library so that it is built as gltf_tinygltf.h configures it: no image decoding (only a
// MASK material's texture is ever decoded, through image_io.h), no external image files read at load
// time, no image writing. Its own warnings are silenced for this file only (scenes/CMakeLists.txt).
#define TINYGLTF_IMPLEMENTATION
#include "gltf_tinygltf.h"
