/* Buffered text output with a small number printer; the platform supplies
 * out_sink() (semihosting on the MCU images, stdout on the host). */
#ifndef LEGSIM_MCU_OUT_H
#define LEGSIM_MCU_OUT_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* platform: writes a NUL-terminated string */
void out_sink(const char *s);

/* Buffered (flushed at '\n', when full, and by out_flush). */
void out_str(const char *s);
void out_char(char c);
void out_int(int64_t v);
void out_uint(uint64_t v);
void out_hex(uint32_t v);
/* n / d and n % d (into *rem if not NULL) without libgcc's 64-bit division */
uint64_t out_udiv64(uint64_t n, uint32_t d, uint32_t *rem);
/* Fixed point with `decimals` digits after the point (0..15); d.ddde+XX for
 * |v| >= 1e9 or for non-zero values that would print as zero; nan/inf spelled out. */
void out_real(double v, int decimals);
void out_flush(void);

#ifdef __cplusplus
}
#endif
#endif
