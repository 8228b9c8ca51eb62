# A library built with a preset (RSM_USER_CONFIG=rsm/config_small.h), library
# only, installed into a scratch prefix: pkg-config's Cflags carry the preset,
# and a consumer built with them alone gets past rsm_localizer_init's
# capacity check (issue 30: rsm.pc dropped it, and such a consumer failed).
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

include(${CMAKE_CURRENT_LIST_DIR}/consumer_common.cmake)

run(${CMAKE_COMMAND} -S ${RSM_SOURCE_DIR} -B ${WORK_DIR}/build -DCMAKE_C_COMPILER=${C_COMPILER}
    -DRSM_USER_CONFIG=rsm/config_small.h -DRSM_BUILD_TESTS=OFF -DRSM_BUILD_TOOLS=OFF -DRSM_TARGET_TESTS=OFF)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build --target rsm)
run(${CMAKE_COMMAND} --install ${WORK_DIR}/build --prefix ${prefix})

rsm_pkg_flags(${prefix} flags)
if(NOT "${flags}" MATCHES "-DRSM_USER_CONFIG=rsm/config_small.h")
  message(FATAL_ERROR "rsm.pc does not carry the preset: ${flags}")
endif()
run(${C_COMPILER} -std=c99 ${RSM_SOURCE_DIR}/tests/consumer/main.c ${flags} -o ${WORK_DIR}/consumer_pc_small)
run(${WORK_DIR}/consumer_pc_small)
