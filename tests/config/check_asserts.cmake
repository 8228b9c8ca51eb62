# The configuration header's compile-time checks: the default configuration
# compiles, and each bad one below stops the compile naming the check it
# broke (so a wrong capacity is found at build time, not as a refusal at
# run time).
#   -DRSM_SOURCE_DIR=... -DC_COMPILER=... -DWORK_DIR=...

file(MAKE_DIRECTORY ${WORK_DIR})
set(src ${WORK_DIR}/asserts.c)
file(WRITE ${src} "#include \"rsm/rsm.h\"\nint main(void) { return 0; }\n")

function(compile out_rc out_text)
  execute_process(COMMAND ${C_COMPILER} -std=c99 -fsyntax-only -I${RSM_SOURCE_DIR}/include ${ARGN} ${src}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(${out_rc} ${rc} PARENT_SCOPE)
  set(${out_text} "${out}${err}" PARENT_SCOPE)
endfunction()

compile(rc text)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the default configuration does not compile:\n${text}")
endif()
# The widest scans and the largest grids compile too: the default lend
# grows with them.
foreach(defs IN ITEMS -DRSM_MAX_BEAMS=4096 -DRSM_GLOBAL_SIDE=200)
  compile(rc text ${defs})
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${defs} does not compile:\n${text}")
  endif()
endforeach()

# Each case: the check's name, then the definitions that break it (comma
# separated).
set(cases
  "global_lend_holds_grids|-DRSM_GLOBAL_LEND_BYTES=1024"
  "global_lend_holds_grids|-DRSM_GLOBAL_SIDE=200,-DRSM_GLOBAL_LEND_BYTES=24576"
  "max_beams_positive|-DRSM_MAX_BEAMS=1")
foreach(c IN LISTS cases)
  string(REPLACE "|" ";" parts "${c}")
  list(GET parts 0 name)
  list(GET parts 1 defs)
  string(REPLACE "," ";" defs "${defs}")
  compile(rc text ${defs})
  if(rc EQUAL 0)
    message(FATAL_ERROR "${defs}: compiled, where the check ${name} should stop it")
  endif()
  if(NOT text MATCHES "rsm_static_assert_${name}")
    message(FATAL_ERROR "${defs}: the compile failed, but not on the check ${name}:\n${text}")
  endif()
  message(STATUS "${defs}: stopped by ${name}")
endforeach()
