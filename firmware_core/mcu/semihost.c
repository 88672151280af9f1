/* Arm semihosting on M-profile: bkpt 0xAB with the operation in r0 and its
 * argument in r1 (QEMU: -semihosting-config enable=on,target=native). */
#include "semihost.h"

#include <stdint.h>

#include "out.h"

#define SYS_WRITE0 0x04
#define SYS_EXIT_EXTENDED 0x20
#define ADP_STOPPED_APPLICATION_EXIT 0x20026

static int32_t semihost_call(int32_t op, const void *arg) {
  register int32_t r0 __asm__("r0") = op;
  register const void *r1 __asm__("r1") = arg;
  __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

void semihost_write0(const char *s) { semihost_call(SYS_WRITE0, s); }

void semihost_exit(int status) {
  out_flush();
  /* The block form lets a 32-bit target report its exit status. */
  const uint32_t block[2] = {ADP_STOPPED_APPLICATION_EXIT, (uint32_t)status};
  semihost_call(SYS_EXIT_EXTENDED, block);
  for (;;) {
  }
}

/* the text sink of out.c */
void out_sink(const char *s) { semihost_write0(s); }
