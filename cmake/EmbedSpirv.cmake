# uvpress_embed_spirv(<target> <shader.comp>...)
# Compiles each GLSL compute shader ahead of time with glslangValidator and writes
# build/shaders/<name>.spv.h holding `const uint32_t <name>_spv[]`. A depfile tracks
# #includes, so editing a shader (or a header it includes) regenerates that one header
# and recompiles only the sources that include it.
function(uvpress_embed_spirv target)
  set(outdir ${CMAKE_BINARY_DIR}/shaders)
  file(MAKE_DIRECTORY ${outdir})
  set(headers)
  foreach(src ${ARGN})
    get_filename_component(name ${src} NAME_WE)
    get_filename_component(abs ${src} ABSOLUTE)
    set(out ${outdir}/${name}.spv.h)
    add_custom_command(
      OUTPUT ${out}
      COMMAND ${GLSLANG_VALIDATOR} -V --target-env vulkan1.1 --quiet
              -I${CMAKE_SOURCE_DIR}/shaders --vn ${name}_spv
              --depfile ${out}.d ${abs} -o ${out}
      DEPENDS ${abs}
      DEPFILE ${out}.d
      COMMENT "glslang ${name}.comp -> SPIR-V"
      VERBATIM)
    list(APPEND headers ${out})
  endforeach()
  add_custom_target(${target}_spirv DEPENDS ${headers})
  add_library(${target} INTERFACE)
  add_dependencies(${target} ${target}_spirv)
  target_include_directories(${target} INTERFACE ${outdir} ${CMAKE_SOURCE_DIR}/shaders)
endfunction()
