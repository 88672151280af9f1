/* Host-only loader of a legsim model file (models/leg.toml, or a robot file such as
 * models/robot.toml that places leg files on a box) into a legsim_model_desc.
 *
 * The one parser of the format: the firmware's compiled-in models are this loader's
 * output too (the build-time tool legsim_model writes it as C data), so a model
 * compiled in and the same file loaded here are equal bit for bit.
 *
 * Messages read "FILE: ITEM: PROBLEM", e.g.
 *   models/leg.toml: joint 'D': body 7 does not exist (ids are 1..6)
 * After its own checks the loader runs legsim_model_check() (the core's
 * semantic checks) and prefixes its message with the file name.
 *
 * Only regular files are read (a FIFO or a device is refused, without blocking),
 * the model file and a robot's leg files alike. A robot's leg files must have the
 * robot's gravity.
 *
 * No exception escapes these functions. Usable from C and C++.
 */
#ifndef LEGSIM_HOST_MODEL_TOML_HPP
#define LEGSIM_HOST_MODEL_TOML_HPP

#include <stddef.h>
#include <stdint.h>

#include "legsim/hexapod.h"
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
 * file order (the order of the compiled-in legsim_model_<symbol>_variants[]).
 * Writes at most max_names names; *n_names gets the total. Only reads the file
 * (use legsim_model_load_toml to validate a variant). */
legsim_status legsim_model_toml_variants(const char *path, char (*names)[LEGSIM_NAME_LEN],
                                         int32_t max_names, int32_t *n_names, char *msg,
                                         size_t msg_len);

/* Loads a hexapod file (models/hexapod.toml; legsim/hexapod.h says what it holds and the
 * ranges it keeps): its six leg files are read by this same loader (the variant each [[leg]]
 * names) and must state the hexapod's gravity in their plane and have a [foot]. A hexapod file
 * given to legsim_model_load_toml is refused (LEGSIM_ERR_BAD_INPUT), and a model file given here.
 * Statuses and messages as legsim_model_load_toml's. */
legsim_status legsim_hexapod_load_toml(const char *path, legsim_hexapod_desc *out, char *msg, size_t msg_len);

/* What legsim_hexapod_load_toml reads (a file with [yoke], [rowing] or [[box_contact]]): 1 a
 * hexapod (it has [[leg]]s), 2 a block (none); 0 anything else: a model file, or a file that
 * cannot be read or does not parse (the loaders then say why). Only reads the file. */
int legsim_toml_is_hexapod_file(const char *path);

#ifdef __cplusplus
}
#endif
#endif /* LEGSIM_HOST_MODEL_TOML_HPP */
