# Cross-build for Cortex-M3 (no FPU: every float operation is a call into
# libgcc's soft-float helpers), e.g. QEMU's mps2-an385.
set(RSM_ARM_CORE m3)
set(RSM_CPU_FLAGS "-mcpu=cortex-m3 -mthumb -mfloat-abi=soft")
include(${CMAKE_CURRENT_LIST_DIR}/toolchain-arm-none-eabi.cmake)
