/* Arm semihosting (bkpt 0xAB on M-profile) for the QEMU images: text out,
 * exit with a status. Nothing here touches newlib's stdio or the heap. */
#ifndef LEGSIM_MCU_SEMIHOST_H
#define LEGSIM_MCU_SEMIHOST_H

#ifdef __cplusplus
extern "C" {
#endif

/* SYS_WRITE0: a NUL-terminated string to the host's stdout. */
void semihost_write0(const char *s);
/* Flushes out.c's buffer, then SYS_EXIT_EXTENDED (ADP_Stopped_ApplicationExit,
 * status): QEMU exits with that status. */
__attribute__((noreturn)) void semihost_exit(int status);

#ifdef __cplusplus
}
#endif
#endif
