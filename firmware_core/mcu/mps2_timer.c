/* CMSDK APB timer 0 of the MPS2 FPGA images (0x40000000), PCLK = 25 MHz in
 * QEMU's mps2-an385/386/500/511 models. A 32-bit down-counter; run free from
 * 0xffffffff, no interrupt. */
#include "mcu_runtime.h"

#define TIMER0_BASE 0x40000000u
#define TIMER_CTRL (*(volatile uint32_t *)(TIMER0_BASE + 0x00u))
#define TIMER_VALUE (*(volatile uint32_t *)(TIMER0_BASE + 0x04u))
#define TIMER_RELOAD (*(volatile uint32_t *)(TIMER0_BASE + 0x08u))

void mcu_timer_start(void) {
  TIMER_CTRL = 0;
  TIMER_RELOAD = 0xffffffffu;
  TIMER_VALUE = 0xffffffffu;
  TIMER_CTRL = 1u; /* enable, PCLK, no interrupt */
}

uint32_t mcu_timer_ticks(void) { return 0xffffffffu - TIMER_VALUE; }
