/* The facts of a build that a dynamic binding needs to mirror legsim.h without
 * its generated legsim/config.h: precision, capacities, feature switches and
 * the sizes of the public structs (python/legsim reads them at load time).
 *
 * Each fact is a (name, value) pair; the names are those of config.h
 * ("LEGSIM_MAX_BODIES", ...) plus "sizeof(<type>)" for the public structs.
 * A reader asks for facts by index until LEGSIM_ERR_BAD_INPUT, so facts can be
 * added without breaking it. Usable from C and C++.
 */
#ifndef LEGSIM_HOST_BUILD_INFO_H
#define LEGSIM_HOST_BUILD_INFO_H

#include <stdint.h>

#include "legsim/legsim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Number of facts. */
int32_t legsim_build_info_count(void);

/* The index-th fact: *name (static string) and *value.
 * LEGSIM_ERR_NULL if name or value is NULL, LEGSIM_ERR_BAD_INPUT if index is
 * outside [0, legsim_build_info_count()); nothing is written then. */
legsim_status legsim_build_info(int32_t index, const char **name, int64_t *value);

#ifdef __cplusplus
}
#endif
#endif /* LEGSIM_HOST_BUILD_INFO_H */
