# The examples (examples/) as their users build them: the built rsm
# installed into a scratch prefix, then each example configured and built
# against it with find_package (its CMakeLists.txt) and with pkg-config (its
# Makefile), warnings as errors. The host example runs on the shipped log
# excerpt: it must exit 0, accept scans and print a finite final pose, the
# version of the library it runs against, and that of rsm.pc and of the CMake
# package. The bare-metal one runs on the host; with arm-none-eabi-gcc
# (ARM_GCC not empty) rsm is also cross-built, library only, installed into
# a second prefix (RSM_WERROR as the build's), and the bare-metal example
# built for the Cortex-M4F against it both ways.
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
set(examples ${RSM_SOURCE_DIR}/examples)
set(toolchain ${RSM_SOURCE_DIR}/cmake/toolchain-arm-none-eabi.cmake)
set(warnings "-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Werror")

include(${CMAKE_CURRENT_LIST_DIR}/consumer_common.cmake)
find_program(MAKE_PROGRAM NAMES gmake make REQUIRED)
find_program(GZIP gzip REQUIRED)
find_program(PKG_CONFIG pkg-config REQUIRED)

# The version include/rsm/version.h gives, MAJOR.MINOR.PATCH.
file(STRINGS ${RSM_SOURCE_DIR}/include/rsm/version.h defines REGEX "^#define RSM_VERSION_(MAJOR|MINOR|PATCH) ")
string(REGEX REPLACE "[^;]*MAJOR ([0-9]+);[^;]*MINOR ([0-9]+);[^;]*PATCH ([0-9]+)" "\\1.\\2.\\3" version "${defines}")

# Configures the example with find_package against prefix_dir (extra: more
# cmake arguments) in dir and builds it; CMake's C flags start from the
# CFLAGS of the environment (a toolchain file's CPU flags are added to them).
function(build_cmake name prefix_dir dir)
  set(ENV{CFLAGS} "${warnings}")
  run(${CMAKE_COMMAND} -S ${examples}/${name} -B ${dir} -DCMAKE_PREFIX_PATH=${prefix_dir} ${ARGN})
  unset(ENV{CFLAGS})
  file(READ ${dir}/CMakeCache.txt cache)
  string(FIND "${cache}" "rsm_DIR:PATH=${prefix_dir}/" at)
  if(at LESS 0)
    message(FATAL_ERROR "${name}: find_package did not take rsm from ${prefix_dir}")
  endif()
  run(${CMAKE_COMMAND} --build ${dir})
endfunction()

# Builds with the example's Makefile in dir, against the rsm.pc under
# prefix_dir; pkg-config must give the header's version.
function(build_make name prefix_dir dir)
  file(GLOB_RECURSE pcs ${prefix_dir}/*/rsm.pc)
  list(GET pcs 0 pc)
  get_filename_component(pcdir ${pc} DIRECTORY)
  set(ENV{PKG_CONFIG_PATH} ${pcdir})
  execute_process(COMMAND ${PKG_CONFIG} --modversion rsm OUTPUT_VARIABLE pc_version OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT pc_version STREQUAL version)
    message(FATAL_ERROR "rsm.pc in ${pcdir} says version '${pc_version}', include/rsm/version.h ${version}")
  endif()
  # On make's command line, as examples/README.md has it.
  unset(ENV{PKG_CONFIG_PATH})
  file(MAKE_DIRECTORY ${dir})
  run(${MAKE_PROGRAM} -C ${dir} -f ${examples}/${name}/Makefile PKG_CONFIG_PATH=${pcdir} "CFLAGS=-O2 ${warnings}"
      ${ARGN})
endfunction()

# Runs the host example (extra arguments: the command before it in a pipe,
# or the log as argument) and checks what it prints; out_var gets it.
function(check_host out_var)
  execute_process(${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "host example failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
  set(num "-?[0-9]+\\.[0-9]+")
  if(NOT out MATCHES "rsm ([^ ]+) \\(headers ([^)]+)\\)")
    message(FATAL_ERROR "host example: no version line\n${out}")
  endif()
  if(NOT CMAKE_MATCH_1 STREQUAL version OR NOT CMAKE_MATCH_2 STREQUAL version)
    message(FATAL_ERROR "host example: library ${CMAKE_MATCH_1}, headers ${CMAKE_MATCH_2}, expected ${version}")
  endif()
  if(NOT out MATCHES "scans ([0-9]+) accepted ([0-9]+)" OR CMAKE_MATCH_2 EQUAL 0)
    message(FATAL_ERROR "host example: no scan accepted\n${out}")
  endif()
  # %.3f prints nan or inf for a pose that is not finite, which this refuses.
  if(NOT out MATCHES "final pose ${num} ${num} ${num}\n")
    message(FATAL_ERROR "host example: no finite final pose\n${out}")
  endif()
  set(${out_var} "${out}" PARENT_SCOPE)
endfunction()

run(${CMAKE_COMMAND} --install ${RSM_BINARY_DIR} --prefix ${prefix})
if(NOT EXISTS ${prefix}/include/rsm/version.h)
  message(FATAL_ERROR "rsm/version.h was not installed")
endif()
file(GLOB_RECURSE config_version_file ${prefix}/*/rsmConfigVersion.cmake)
file(READ ${config_version_file} config_version)
if(NOT config_version MATCHES "set\\(PACKAGE_VERSION \"${version}\"\\)")
  message(FATAL_ERROR "rsmConfigVersion.cmake does not carry version ${version}")
endif()

foreach(name host baremetal)
  build_cmake(${name} ${prefix} ${WORK_DIR}/${name}-cmake -DCMAKE_C_COMPILER=${C_COMPILER})
  build_make(${name} ${prefix} ${WORK_DIR}/${name}-make CC=${C_COMPILER})
endforeach()

run(${WORK_DIR}/baremetal-cmake/rsm_example_baremetal)
run(${WORK_DIR}/baremetal-make/rsm_example_baremetal)

set(log ${RSM_SOURCE_DIR}/tests/data/intel_head.clf.gz)
check_host(by_pipe COMMAND ${GZIP} -dc ${log} COMMAND ${WORK_DIR}/host-cmake/rsm_example_host)
execute_process(COMMAND ${GZIP} -dc ${log} OUTPUT_FILE ${WORK_DIR}/intel_head.clf RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cannot unpack ${log}")
endif()
check_host(by_file COMMAND ${WORK_DIR}/host-cmake/rsm_example_host ${WORK_DIR}/intel_head.clf)
if(NOT by_pipe STREQUAL by_file)
  message(FATAL_ERROR "the host example read the log differently from stdin and from a file")
endif()
check_host(by_make COMMAND ${WORK_DIR}/host-make/rsm_example_host ${WORK_DIR}/intel_head.clf)

if(NOT ARM_GCC)
  message(STATUS "arm-none-eabi-gcc not found: the bare-metal example is not cross-built")
  return()
endif()
# Library only, as a firmware project installs it: no tests, tools, ports or images.
run(${CMAKE_COMMAND} -S ${RSM_SOURCE_DIR} -B ${WORK_DIR}/arm-rsm -DCMAKE_TOOLCHAIN_FILE=${toolchain}
    -DCMAKE_BUILD_TYPE=MinSizeRel -DRSM_WERROR=${RSM_WERROR} -DRSM_BUILD_BAREMETAL=OFF)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/arm-rsm)
run(${CMAKE_COMMAND} --install ${WORK_DIR}/arm-rsm --prefix ${WORK_DIR}/arm-prefix)
build_cmake(baremetal ${WORK_DIR}/arm-prefix ${WORK_DIR}/baremetal-arm-cmake -DCMAKE_TOOLCHAIN_FILE=${toolchain})
build_make(baremetal ${WORK_DIR}/arm-prefix ${WORK_DIR}/baremetal-arm-make CROSS=arm-none-eabi-)
# Both are ARM executables: ELF, e_machine 40 (EM_ARM) at byte 18.
foreach(elf ${WORK_DIR}/baremetal-arm-cmake/rsm_example_baremetal.elf
            ${WORK_DIR}/baremetal-arm-make/rsm_example_baremetal.elf)
  file(READ ${elf} head LIMIT 20 HEX)
  if(NOT head MATCHES "^7f454c46.*2800$")
    message(FATAL_ERROR "${elf} is not an ARM executable (${head})")
  endif()
endforeach()
