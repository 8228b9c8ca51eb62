# Cross-build for Cortex-M0+ (ARMv6-M, no FPU, no divide instruction), e.g.
# the RP2040.
set(RSM_ARM_CORE m0plus)
set(RSM_CPU_FLAGS "-mcpu=cortex-m0plus -mthumb -mfloat-abi=soft")
include(${CMAKE_CURRENT_LIST_DIR}/toolchain-arm-none-eabi.cmake)
