# The dependency rules of DESIGN.md ("Layout"), checked on every #include "..." of the
# source tree: `cmake -DROOT=<repository> -P tests/layers.cmake` lists every include that
# breaks them and fails. Run by CTest as `layers`.
#
# An include is resolved as the compiler resolves a quoted include: next to the including
# file first, then under host/, engine/include/ and shaders/ (the public include
# directories), then engine/ (the backends' private one: a host include found only there
# does not compile, and is reported here by name). What resolves to none of them is a
# library header and is not checked.
#  - host/<stage>/ may include its own stage and the stages listed for it below;
#    "engine" means the engine interface, engine/include/engine.h, and nothing else of engine/.
#  - engine/ never includes host/.
cmake_minimum_required(VERSION 3.20)
if(NOT ROOT)
  message(FATAL_ERROR "usage: cmake -DROOT=<repository> -P layers.cmake")
endif()

set(allowed_core "")
set(allowed_io "core")
set(allowed_solve "core")
set(allowed_flatten "core;solve")
set(allowed_bo "core")
set(allowed_perceptual "core;bo;solve;engine")
set(allowed_atlas "core;io;engine")
set(allowed_eval "core;io;atlas;flatten;engine")
set(allowed_pipeline "core;io;solve;flatten;bo;perceptual;atlas;eval;engine")
set(allowed_batch "core;io;solve;flatten;bo;perceptual;atlas;eval;pipeline;engine")
set(stages core io solve flatten bo perceptual atlas eval pipeline batch)

set(violations "")
set(checked 0)
file(GLOB_RECURSE sources RELATIVE "${ROOT}" "${ROOT}/host/*.h" "${ROOT}/host/*.cpp" "${ROOT}/engine/*.h"
     "${ROOT}/engine/*.cpp")
foreach(rel IN LISTS sources)
  string(REPLACE "/" ";" parts "${rel}")
  list(GET parts 0 top)
  if(top STREQUAL "host")
    list(GET parts 1 stage)
    if(NOT stage IN_LIST stages)
      list(APPEND violations "${rel}: host/${stage} is not a stage of DESIGN.md's table")
      continue()
    endif()
  endif()
  get_filename_component(dir "${ROOT}/${rel}" DIRECTORY)
  file(STRINGS "${ROOT}/${rel}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
  foreach(line IN LISTS lines)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*\"([^\"]+)\".*" "\\1" inc "${line}")
    math(EXPR checked "${checked} + 1")
    # Resolve: next to the file, then the public include directories.
    set(target "")
    if(EXISTS "${dir}/${inc}")
      file(RELATIVE_PATH target "${ROOT}" "${dir}/${inc}")
    else()
      foreach(base host engine/include shaders engine)
        if(EXISTS "${ROOT}/${base}/${inc}")
          set(target "${base}/${inc}")
          break()
        endif()
      endforeach()
    endif()
    if(target STREQUAL "")
      continue()  # a library header
    endif()
    string(REPLACE "/" ";" tparts "${target}")
    list(GET tparts 0 ttop)
    if(top STREQUAL "engine")
      if(ttop STREQUAL "host")
        list(APPEND violations "${rel}: includes ${target} (nothing in engine/ includes host/)")
      endif()
      continue()
    endif()
    # host/<stage>
    if(ttop STREQUAL "host")
      list(GET tparts 1 tstage)
      if(tstage STREQUAL stage OR tstage IN_LIST allowed_${stage})
        continue()
      endif()
      string(REPLACE ";" ", " may "${allowed_${stage}}")
      list(APPEND violations "${rel}: includes ${target} (host/${stage} may depend on: ${may})")
    elseif(ttop STREQUAL "engine")
      if(target STREQUAL "engine/include/engine.h" AND "engine" IN_LIST allowed_${stage})
        continue()
      endif()
      list(APPEND violations "${rel}: includes ${target} (host/${stage} may use only the engine interface, engine/include/engine.h, and only where DESIGN.md allows it)")
    elseif(ttop STREQUAL "shaders")
      list(APPEND violations "${rel}: includes ${target} (shaders/ are the engine's; the host reaches them through engine.h)")
    endif()
  endforeach()
endforeach()

list(LENGTH violations n)
if(n GREATER 0)
  list(JOIN violations "\n  " text)
  message(FATAL_ERROR "${n} include(s) break DESIGN.md's dependency rules:\n  ${text}")
endif()
message(STATUS "layers: ${checked} quoted includes checked, every one within DESIGN.md's rules")
