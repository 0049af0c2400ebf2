# Every dependency comes from Debian 12 packages (scripts/install-deps.sh installs them).
find_package(Threads REQUIRED)
find_package(glm REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(TBB REQUIRED)
# Debian's tinyobjloader calls its version "2rc10": ask for none.
find_package(tinyobjloader REQUIRED)
# glTF files (scenes/src/gltf_loader.cpp): libtinygltf-dev's header, compiled into shadowlab_scenes
# without image decoding (scenes/src/gltf_tinygltf.cpp), so its shared library is not linked.
find_path(TINYGLTF_INCLUDE_DIR tiny_gltf.h REQUIRED DOC "libtinygltf-dev's tiny_gltf.h")
# Image files (scenes/src/image_io.h): SHADOWLAB_IMAGE_IO=oiio (the default) reads and writes them
# with OpenImageIO; exr-png with OpenEXR and libpng, whose few MB of libraries fit a bundle for a
# bare machine (scripts/device-bundle.sh), where OpenImageIO pulls in ~390 MB (GDAL, ffmpeg, ...).
set(SHADOWLAB_IMAGE_IO oiio CACHE STRING "Image file library: oiio (OpenImageIO) or exr-png (OpenEXR + libpng)")
set_property(CACHE SHADOWLAB_IMAGE_IO PROPERTY STRINGS oiio exr-png)
if(NOT SHADOWLAB_IMAGE_IO MATCHES "^(oiio|exr-png)$")
  message(FATAL_ERROR "SHADOWLAB_IMAGE_IO is \"${SHADOWLAB_IMAGE_IO}\"; expected oiio or exr-png")
endif()
# Debian's OpenImageIO CMake config demands the openimageio-tools binaries and lists a missing
# /usr/include/opencv4; its pkg-config file has neither problem. With exr-png it is optional: two
# tests read pictures with it, and tests/scenes_image_io_test.cpp checks one library against the other.
find_package(PkgConfig REQUIRED)
if(SHADOWLAB_IMAGE_IO STREQUAL "oiio")
  pkg_check_modules(OIIO REQUIRED GLOBAL IMPORTED_TARGET OpenImageIO)
else()
  pkg_check_modules(OIIO QUIET GLOBAL IMPORTED_TARGET OpenImageIO)
endif()
if(TARGET PkgConfig::OIIO)
  add_library(OpenImageIO::OpenImageIO ALIAS PkgConfig::OIIO)
endif()
# OpenEXR (libopenexr-dev) + libpng (libpng-dev): the exr-png implementation; with oiio only the
# cross-check test needs them, so they are optional there.
if(SHADOWLAB_IMAGE_IO STREQUAL "exr-png")
  find_package(OpenEXR 3 REQUIRED CONFIG)  # target: OpenEXR::OpenEXR
  find_package(PNG REQUIRED)               # target: PNG::PNG
else()
  find_package(OpenEXR 3 QUIET CONFIG)
  find_package(PNG QUIET)
endif()
find_package(embree 3 REQUIRED)      # target: embree (no namespace)
find_package(Vulkan REQUIRED)
find_program(GLSLANG_VALIDATOR glslangValidator REQUIRED)
find_package(GTest REQUIRED)
find_package(benchmark REQUIRED)
