# UBSan's vptr check (part of -fsanitize=undefined) reads the RTTI of every polymorphic class a
# translation unit touches, and Debian's glslang is built without RTTI: a file that uses
# glslang::TShader or TProgram under that check fails to link ("undefined reference to typeinfo
# for glslang::TShader"). Those files alone are built with -fno-sanitize=vptr, and only when the
# flags ask for the check; everything else keeps it. Used by raster/CMakeLists.txt and by the
# guard that links such a file under UBSan (tests/sanitizers/glslang_vptr).
function(shadowlab_glslang_sources)
  string(TOUPPER "${CMAKE_BUILD_TYPE}" config)
  set(flags "${CMAKE_CXX_FLAGS} ${CMAKE_CXX_FLAGS_${config}}")
  get_directory_property(options COMPILE_OPTIONS)
  string(APPEND flags " ${options}")
  if(flags MATCHES "-fsanitize=[^ ;]*(undefined|vptr)")
    set_source_files_properties(${ARGN} PROPERTIES COMPILE_OPTIONS -fno-sanitize=vptr)
  endif()
endfunction()
