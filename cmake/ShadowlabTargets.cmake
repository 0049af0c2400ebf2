# Which library a test (tests/<unit>_test.cpp, compiled into that library's test executable) or
# benchmark (bench/<unit>_bench.cpp) links, from the prefix of its name. One place for tests/ and
# bench/, so a new prefix is added once.
#   scenes_*               -> shadowlab_scenes
#   reference_*            -> shadowlab_reference
#   raster_*reference*     -> shadowlab_raster + shadowlab_reference (checked against Embree)
#   raster_*               -> shadowlab_raster
#   gate_*                 -> shadowlab_gate (no renderer: see tests/check_no_renderer.cmake)
#   compare_metrics*       -> shadowlab_classify
#   everything else        -> shadowlab_study (sweep_*, stability_*, report_*, robustness_*, and
#                             compare_* that render: compare_cli, compare_end_to_end, compare_frames)
function(shadowlab_library_for name out)
  if(name MATCHES "^scenes_")
    set(libs shadowlab_scenes)
  elseif(name MATCHES "^reference_")
    set(libs shadowlab_reference)
  elseif(name MATCHES "^raster_.*reference")
    set(libs shadowlab_raster shadowlab_reference)
  elseif(name MATCHES "^raster_")
    set(libs shadowlab_raster)
  elseif(name MATCHES "^gate_")
    set(libs shadowlab_gate)
  elseif(name MATCHES "^compare_metrics")
    set(libs shadowlab_classify)
  else()
    set(libs shadowlab_study)
  endif()
  set(${out} ${libs} PARENT_SCOPE)
endfunction()

# shadowlab_library(<target> <dir> [PUBLIC libs...] [PRIVATE libs...]): a static library from
# <dir>/src/*.cpp with public headers in <dir>/include.
function(shadowlab_library target dir)
  cmake_parse_arguments(ARG "" "" "PUBLIC;PRIVATE" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS "${dir}/src/*.cpp")
  add_library(${target} STATIC ${sources})
  target_include_directories(${target} PUBLIC "${dir}/include")
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
endfunction()
