/* Host-only run-time loader of a legsim model TOML (models/leg.toml) into a
 * legsim_model_desc.
 *
 * The mapping and every check (and its message) are those of the firmware's
 * code generator firmware_core/tools/model_codegen.py: one model file, one
 * meaning, whether it is compiled in or loaded at run time (tests/model checks
 * that both give the same descriptions and the same messages).
 *
 * Messages read "FILE: ITEM: PROBLEM", e.g.
 *   models/leg.toml: joint 'D': body 7 does not exist (ids are 1..6)
 * After its own checks the loader runs legsim_model_check() (the core's
 * semantic checks) and prefixes its message with the file name.
 *
 * No exception escapes these functions. Usable from C and C++.
 */
#ifndef LEGSIM_HOST_MODEL_TOML_HPP
#define LEGSIM_HOST_MODEL_TOML_HPP

#include <stddef.h>
#include <stdint.h>

#include "legsim/legsim.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LEGSIM_DEFAULT_VARIANT "revolute"

/* Loads one variant of the model file at path ("revolute", the default, when
 * variant is NULL or empty; else a [variant.X] of the file).
 * Returns LEGSIM_OK and fills *out, or:
 *   LEGSIM_ERR_NULL       path or out is NULL
 *   LEGSIM_ERR_BAD_INPUT  the file cannot be read, or no such variant
 *   LEGSIM_ERR_MODEL      TOML syntax error or an invalid model
 *   LEGSIM_ERR_CAPACITY   more items than the build's LEGSIM_MAX_*
 * and writes a one-line message into msg (if not NULL; truncated to msg_len).
 * *out is written only on LEGSIM_OK. */
legsim_status legsim_model_load_toml(const char *path, const char *variant,
                                     legsim_model_desc *out, char *msg, size_t msg_len);

/* The same from TOML text in memory (text_len bytes); source_name stands for the
 * file in the messages. */
legsim_status legsim_model_parse_toml(const char *text, size_t text_len, const char *source_name,
                                      const char *variant, legsim_model_desc *out, char *msg,
                                      size_t msg_len);

/* Variant names of the model file: "revolute" first, then its [variant.X] tables in
 * file order (the order of the code generator's legsim_model_<symbol>_variants[]).
 * Writes at most max_names names; *n_names gets the total. Only reads the file
 * (use legsim_model_load_toml to validate a variant). */
legsim_status legsim_model_toml_variants(const char *path, char (*names)[LEGSIM_NAME_LEN],
                                         int32_t max_names, int32_t *n_names, char *msg,
                                         size_t msg_len);

#ifdef __cplusplus
}
#endif
#endif /* LEGSIM_HOST_MODEL_TOML_HPP */
