# rsm as a subproject (subproject/CMakeLists.txt checks what it defines):
# configured, built and run on the host; with arm-none-eabi-gcc (ARM_GCC
# not empty) configured again with the Cortex-M4F toolchain, where the
# firmware images would otherwise appear, and its library built.
file(REMOVE_RECURSE ${WORK_DIR})
include(${CMAKE_CURRENT_LIST_DIR}/consumer_common.cmake)

run(${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR}/subproject -B ${WORK_DIR}/host
    -DRSM_SOURCE_DIR=${RSM_SOURCE_DIR} -DCMAKE_C_COMPILER=${C_COMPILER})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/host)
run(${WORK_DIR}/host/parent)

if(NOT ARM_GCC)
  message(STATUS "arm-none-eabi-gcc not found: no cross-compiled subproject")
  return()
endif()
run(${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR}/subproject -B ${WORK_DIR}/arm -DRSM_SOURCE_DIR=${RSM_SOURCE_DIR}
    -DCMAKE_TOOLCHAIN_FILE=${RSM_SOURCE_DIR}/cmake/toolchain-arm-none-eabi.cmake)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/arm --target rsm rsm_port_baremetal)
