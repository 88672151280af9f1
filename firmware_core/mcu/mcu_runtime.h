/* Board-independent bits of the MCU images: exit codes, stack use, cycle timer. */
#ifndef LEGSIM_MCU_RUNTIME_H
#define LEGSIM_MCU_RUNTIME_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* exit statuses of the images (QEMU exits with them) */
enum {
  MCU_EXIT_OK = 0,
  MCU_EXIT_API = 1,        /* a legsim call failed */
  MCU_EXIT_CHECK = 2,      /* a self-check failed (storage size, ...) */
  MCU_EXIT_FAULT = 100,    /* HardFault / MemManage / BusFault / UsageFault */
  MCU_EXIT_HEAP = 101      /* something called malloc/free/new/delete */
};

/* Stack region (linker script) and its high-water mark (painted at reset). */
size_t mcu_stack_size(void);
size_t mcu_stack_used(void);

/* A free-running 32-bit tick counter (CMSDK APB timer 0 of the MPS2 boards,
 * clocked at MCU_TIMER_HZ). Under QEMU's -icount shift=0, virtual time runs
 * 1 ns per instruction, so one tick is MCU_TIMER_HZ-th of a second =
 * 1e9 / MCU_TIMER_HZ instructions. */
#define MCU_TIMER_HZ 25000000u
#define MCU_INSNS_PER_TICK (1000000000u / MCU_TIMER_HZ)
void mcu_timer_start(void);
uint32_t mcu_timer_ticks(void); /* ticks since mcu_timer_start (wraps after 2^32) */

#ifdef __cplusplus
}
#endif
#endif
