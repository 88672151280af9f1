/* sin and cos in float for the images' own printing (leg_report.c): the core's reduction
 * and polynomials (firmware_core/src/planar/kernel_trig.hpp), so a float image links no libm
 * trigonometry (newlib's sinf/cosf and their tables were 4.2 KB of the M4F's flash). */
#ifndef LEGSIM_MCU_TRIG_H
#define LEGSIM_MCU_TRIG_H

#ifdef __cplusplus
extern "C" {
#endif

void mcu_sincosf(float x, float *s, float *c);

#ifdef __cplusplus
}
#endif

#endif
