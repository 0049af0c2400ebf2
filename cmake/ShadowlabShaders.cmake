# shadowlab_shaders(TARGET SOURCE_DIR OUT_DIR shader... [INCLUDE_DIRS dir...] [DEPENDS header...]):
# compiles each GLSL shader of SOURCE_DIR at build time to SPIR-V embedded as a C array
# (glslangValidator --vn kSpv_<name with . -> _>) in OUT_DIR/<name>.h, and adds a custom target
# TARGET that builds them all. INCLUDE_DIRS are searched by #include (GL_GOOGLE_include_directive,
# SOURCE_DIR always); every shader is rebuilt when one of the DEPENDS headers changes.
function(shadowlab_shaders target source_dir out_dir)
  cmake_parse_arguments(PARSE_ARGV 3 arg "" "" "INCLUDE_DIRS;DEPENDS")
  file(MAKE_DIRECTORY "${out_dir}")
  set(includes "-I${source_dir}")
  foreach(dir ${arg_INCLUDE_DIRS})
    list(APPEND includes "-I${dir}")
  endforeach()
  set(headers)
  foreach(shader ${arg_UNPARSED_ARGUMENTS})
    string(REPLACE "." "_" symbol "${shader}")
    set(header "${out_dir}/${symbol}.h")
    add_custom_command(
      OUTPUT "${header}"
      COMMAND ${GLSLANG_VALIDATOR} -V --target-env vulkan1.3 --quiet ${includes} --vn kSpv_${symbol}
              -o "${header}" "${source_dir}/${shader}"
      DEPENDS "${source_dir}/${shader}" ${arg_DEPENDS}
      COMMENT "glslangValidator ${shader}"
      VERBATIM)
    list(APPEND headers "${header}")
  endforeach()
  add_custom_target(${target} DEPENDS ${headers})
endfunction()
