# ctest technique_ubsan_links_glslang: configure, build (-O0: the link is the test) and run the
# guard project beside the build. Fails at the first step that does. HOST_CXX_FLAGS and
# HOST_LINK_FLAGS: the build's own (its libshadowlab_scenes may need the ASan runtime).
file(REMOVE_RECURSE "${BUILD_DIR}")
foreach(step configure build run)
  if(step STREQUAL "configure")
    set(command ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/sanitizers/glslang_vptr -B ${BUILD_DIR}
                -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE= -DCMAKE_CXX_COMPILER_LAUNCHER=
                "-DCMAKE_CXX_FLAGS=${HOST_CXX_FLAGS} -fsanitize=undefined -fno-sanitize-recover=undefined -O0"
                "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=undefined ${HOST_LINK_FLAGS}" -DSOURCE_DIR=${SOURCE_DIR} -DSPV_DIR=${SPV_DIR}
                -DSCENES_LIB=${SCENES_LIB})
  elseif(step STREQUAL "build")
    set(command ${CMAKE_COMMAND} --build ${BUILD_DIR})
  else()
    set(command ${BUILD_DIR}/probe)
  endif()
  execute_process(COMMAND ${command} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "glslang_vptr guard: ${step} failed (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "${step}: ok ${out}")
endforeach()
