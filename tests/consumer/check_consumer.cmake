# Install the built rsm into a scratch prefix, then build and run a consumer
# twice: with find_package(rsm) and with pkg-config (plain compiler call);
# each also once with RSM_MAX_BEAMS other than the library's, where
# rsm_localizer_init must refuse (RSM_ERR_CONFIG) rather than overflow.
# SANITIZE_FLAGS (may be empty): compiler and linker flags for the consumers,
# given by the sanitizer build; each consumer must then report that it runs
# under AddressSanitizer, so an uninstrumented build cannot pass for one.
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

separate_arguments(sanitize UNIX_COMMAND "${SANITIZE_FLAGS}")

include(${CMAKE_CURRENT_LIST_DIR}/consumer_common.cmake)

# Runs a built consumer; under SANITIZE_FLAGS it must say it is instrumented.
function(run_consumer exe)
  execute_process(COMMAND ${exe} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${exe}\n${out}\n${err}")
  endif()
  if(sanitize AND NOT out MATCHES "AddressSanitizer on")
    message(FATAL_ERROR "${exe} was built with ${SANITIZE_FLAGS} but does not run under AddressSanitizer:\n${out}")
  endif()
  message(STATUS "${out}")
endfunction()

run(${CMAKE_COMMAND} --install ${RSM_BINARY_DIR} --prefix ${prefix})
run(${CMAKE_COMMAND} -S ${RSM_SOURCE_DIR}/tests/consumer -B ${WORK_DIR}/build
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_C_COMPILER=${C_COMPILER}
    "-DCMAKE_C_FLAGS=${SANITIZE_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${SANITIZE_FLAGS}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run_consumer(${WORK_DIR}/build/consumer)
run_consumer(${WORK_DIR}/build/consumer_mismatch)

rsm_pkg_flags(${prefix} flags)

# Each installed header stands alone with only the installed include folder
# (no internal header of src/ may leak into one), in C99.
file(GLOB installed_headers ${prefix}/include/rsm/*.h)
list(LENGTH installed_headers n_headers)
if(n_headers LESS 10)
  message(FATAL_ERROR "only ${n_headers} headers installed in ${prefix}/include/rsm")
endif()
foreach(h ${installed_headers})
  get_filename_component(name ${h} NAME)
  file(WRITE ${WORK_DIR}/alone_${name}.c "#include \"rsm/${name}\"\nint main(void) { return 0; }\n")
  run(${C_COMPILER} -std=c99 -Wall -Wextra -Wpedantic -Werror -fsyntax-only ${flags} ${WORK_DIR}/alone_${name}.c)
endforeach()
foreach(internal grid.h tilemap.h mapmatch.h ransac.h icp.h ekf.h)
  if(EXISTS ${prefix}/include/rsm/${internal})
    message(FATAL_ERROR "internal header ${internal} was installed")
  endif()
endforeach()
run(${C_COMPILER} -std=c99 ${sanitize} ${RSM_SOURCE_DIR}/tests/consumer/main.c ${flags} -o ${WORK_DIR}/consumer_pc)
run_consumer(${WORK_DIR}/consumer_pc)
run(${C_COMPILER} -std=c99 ${sanitize} -DRSM_MAX_BEAMS=181 -DEXPECT_MISMATCH=1 ${RSM_SOURCE_DIR}/tests/consumer/main.c
    ${flags} -o ${WORK_DIR}/consumer_pc_mismatch)
run_consumer(${WORK_DIR}/consumer_pc_mismatch)
