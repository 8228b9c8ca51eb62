# Shared by the install checks (check_consumer.cmake, check_pc_preset.cmake).

# Runs a command; stops the check with its output when it fails.
function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGV}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()

# pkg-config's compiler and linker flags for the rsm installed under prefix,
# as a list, in out_var.
function(rsm_pkg_flags prefix out_var)
  find_program(PKG_CONFIG pkg-config REQUIRED)
  file(GLOB_RECURSE pcs ${prefix}/*/rsm.pc)
  list(GET pcs 0 pc)
  get_filename_component(pcdir ${pc} DIRECTORY)
  set(ENV{PKG_CONFIG_PATH} ${pcdir})
  execute_process(COMMAND ${PKG_CONFIG} --cflags --libs --static rsm
    OUTPUT_VARIABLE flags OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pkg-config cannot find rsm in ${pcdir}")
  endif()
  separate_arguments(flags UNIX_COMMAND "${flags}")
  set(${out_var} ${flags} PARENT_SCOPE)
endfunction()
