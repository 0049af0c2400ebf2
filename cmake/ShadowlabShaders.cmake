# shadowlab_shaders(TARGET SOURCE_DIR OUT_DIR shader...): compiles each GLSL shader of SOURCE_DIR at
# build time to SPIR-V embedded as a C array (glslangValidator --vn kSpv_<name with . -> _>) in
# OUT_DIR/<name>.h, and adds a custom target TARGET that builds them all.
function(shadowlab_shaders target source_dir out_dir)
  file(MAKE_DIRECTORY "${out_dir}")
  set(headers)
  foreach(shader ${ARGN})
    string(REPLACE "." "_" symbol "${shader}")
    set(header "${out_dir}/${symbol}.h")
    add_custom_command(
      OUTPUT "${header}"
      COMMAND ${GLSLANG_VALIDATOR} -V --target-env vulkan1.3 --quiet --vn kSpv_${symbol}
              -o "${header}" "${source_dir}/${shader}"
      DEPENDS "${source_dir}/${shader}"
      COMMENT "glslangValidator ${shader}"
      VERBATIM)
    list(APPEND headers "${header}")
  endforeach()
  add_custom_target(${target} DEPENDS ${headers})
endfunction()
