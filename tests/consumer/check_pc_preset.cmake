# A library built with a preset (RSM_USER_CONFIG=rsm/config_small.h), library
# only, installed into a scratch prefix: pkg-config's Cflags carry the preset,
# and a consumer built with them alone gets past rsm_localizer_init's
# capacity check (issue 30: rsm.pc dropped it, and such a consumer failed).
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGV}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()

run(${CMAKE_COMMAND} -S ${RSM_SOURCE_DIR} -B ${WORK_DIR}/build -DCMAKE_C_COMPILER=${C_COMPILER}
    -DRSM_USER_CONFIG=rsm/config_small.h -DRSM_BUILD_TESTS=OFF -DRSM_BUILD_TOOLS=OFF -DRSM_TARGET_TESTS=OFF)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build --target rsm)
run(${CMAKE_COMMAND} --install ${WORK_DIR}/build --prefix ${prefix})

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
if(NOT flags MATCHES "-DRSM_USER_CONFIG=rsm/config_small.h")
  message(FATAL_ERROR "rsm.pc does not carry the preset: ${flags}")
endif()
separate_arguments(flags UNIX_COMMAND "${flags}")
run(${C_COMPILER} -std=c99 ${RSM_SOURCE_DIR}/tests/consumer/main.c ${flags} -o ${WORK_DIR}/consumer_pc_small)
run(${WORK_DIR}/consumer_pc_small)
