# Every dependency comes from Debian 12 packages (scripts/install-deps.sh installs them).
find_package(Threads REQUIRED)
find_package(glm REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(TBB REQUIRED)
# Debian's tinyobjloader calls its version "2rc10": ask for none.
find_package(tinyobjloader REQUIRED)
# Debian's OpenImageIO CMake config demands the openimageio-tools binaries and lists a missing
# /usr/include/opencv4; its pkg-config file has neither problem.
find_package(PkgConfig REQUIRED)
pkg_check_modules(OIIO REQUIRED GLOBAL IMPORTED_TARGET OpenImageIO)
add_library(OpenImageIO::OpenImageIO ALIAS PkgConfig::OIIO)
find_package(embree 3 REQUIRED)      # target: embree (no namespace)
find_package(Vulkan REQUIRED)
find_program(GLSLANG_VALIDATOR glslangValidator REQUIRED)
find_package(GTest REQUIRED)
find_package(benchmark REQUIRED)
