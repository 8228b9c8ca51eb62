/* The library's version. These three numbers are the one place it is
 * written: CMakeLists.txt reads them into project(VERSION), from which the
 * CMake package (rsmConfigVersion.cmake) and rsm.pc take theirs. A header,
 * not a file generated at configure time, so that compiling the sources of src/
 * straight into an image (no CMake, docs/building.md) sees the same version.
 * Semantic versioning: MAJOR changes break the API. */
#ifndef RSM_VERSION_H
#define RSM_VERSION_H

#ifdef __cplusplus
extern "C" {
#endif

#define RSM_VERSION_MAJOR 0
#define RSM_VERSION_MINOR 1
#define RSM_VERSION_PATCH 0

/* Two levels, so that the numbers' values are turned into text, not their names. */
#define RSM_VERSION_STR_(x) #x
#define RSM_VERSION_STR(x) RSM_VERSION_STR_(x)

/* "MAJOR.MINOR.PATCH", a string literal: "0.1.0". */
#define RSM_VERSION_STRING \
    RSM_VERSION_STR(RSM_VERSION_MAJOR) "." RSM_VERSION_STR(RSM_VERSION_MINOR) "." RSM_VERSION_STR(RSM_VERSION_PATCH)

/* The version the library was built as: RSM_VERSION_STRING of its own
 * build, a ROM string, never NULL. An application that compares it with its
 * own RSM_VERSION_STRING finds out whether it runs against the library its
 * headers came from (a shared library replaced underneath it). Reentrant,
 * ISR-safe. */
const char *rsm_version(void);

#ifdef __cplusplus
}
#endif

#endif /* RSM_VERSION_H */
