# cmake -DEXECUTABLE=<file> -P check_no_renderer.cmake: fails when ldd shows that <file> loads
# Embree or Vulkan (the renderers' shared libraries). The static shadowlab libraries leave no
# trace in ldd, but whatever they pull in does: a gate linked to raster or reference would load
# libvulkan or libembree.
if(NOT EXECUTABLE OR NOT EXISTS "${EXECUTABLE}")
  message(FATAL_ERROR "check_no_renderer: no executable \"${EXECUTABLE}\"")
endif()
execute_process(COMMAND ldd "${EXECUTABLE}" OUTPUT_VARIABLE libraries RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "check_no_renderer: ldd ${EXECUTABLE} failed (${status})")
endif()
string(REGEX MATCHALL "lib(embree|vulkan)[^ \t\n]*" renderers "${libraries}")
if(renderers)
  list(REMOVE_DUPLICATES renderers)
  # RENDERER_LINKED: the token gate_links_no_renderer_detects_renderers looks for.
  message(FATAL_ERROR "RENDERER_LINKED: ${EXECUTABLE} loads ${renderers}; expected no renderer library")
endif()
message(STATUS "${EXECUTABLE}: no Embree, no Vulkan")
