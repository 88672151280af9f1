/* Minimal Cortex-M startup for the QEMU MPS2 images (no newlib crt0).
 *
 * Reset: FPU on (CPACR), .data copied from flash, .bss zeroed, the stack
 * painted (for the high-water mark), constructors run, main() called, and its
 * status handed to the host through semihosting. There is no atexit, no
 * destructors, no exit(): newlib's crt0 -> atexit -> __register_exitproc path
 * (which can reach for malloc) is never linked. */
#include <stddef.h>
#include <stdint.h>

#include "mcu_runtime.h"
#include "out.h"
#include "semihost.h"

/* linker script symbols (cortex_m_sections.ld) */
extern uint32_t __data_load__[], __data_start__[], __data_end__[];
extern uint32_t __bss_start__[], __bss_end__[];
extern uint32_t __stack_limit__[], __stack_top__[];
extern void (*__preinit_array_start[])(void);
extern void (*__preinit_array_end[])(void);
extern void (*__init_array_start[])(void);
extern void (*__init_array_end[])(void);

int main(void);

#define STACK_PAINT 0xa5a5a5a5u
#define CPACR (*(volatile uint32_t *)0xe000ed88u)

__attribute__((noreturn, used)) void mcu_reset_c(void) {
  /* .data and .bss */
  for (uint32_t *src = __data_load__, *dst = __data_start__; dst < __data_end__;) *dst++ = *src++;
  for (uint32_t *dst = __bss_start__; dst < __bss_end__;) *dst++ = 0;

  /* paint the stack below the current frame, leaving a margin */
  uint32_t *sp_now = (uint32_t *)__builtin_frame_address(0);
  for (uint32_t *p = __stack_limit__; p < sp_now - 16; ++p) *p = STACK_PAINT;

  /* C++ constructors, if any (the core has none; Eigen's are constexpr) */
  for (void (**f)(void) = __preinit_array_start; f < __preinit_array_end; ++f) (*f)();
  for (void (**f)(void) = __init_array_start; f < __init_array_end; ++f) (*f)();

  semihost_exit(main());
}

/* Reset entry: turn the FPU on before any C code can use a VFP register, then C. */
__attribute__((naked, noreturn)) void Reset_Handler(void) {
  __asm__ volatile(
      "movw r0, #0xed88\n"
      "movt r0, #0xe000\n" /* CPACR */
      "ldr r1, [r0]\n"
      "orr r1, r1, #(0xf << 20)\n" /* CP10, CP11: full access */
      "str r1, [r0]\n"
      "dsb\n"
      "isb\n"
      "b mcu_reset_c\n");
}

size_t mcu_stack_size(void) {
  return (size_t)((uintptr_t)__stack_top__ - (uintptr_t)__stack_limit__);
}

size_t mcu_stack_used(void) {
  const uint32_t *p = __stack_limit__;
  while (p < __stack_top__ && *p == STACK_PAINT) ++p;
  return (size_t)((uintptr_t)__stack_top__ - (uintptr_t)p);
}

/* ---- faults: report and leave QEMU with a distinct status --------------- */
#define SCB_CFSR (*(volatile uint32_t *)0xe000ed28u)
#define SCB_HFSR (*(volatile uint32_t *)0xe000ed2cu)
#define SCB_MMFAR (*(volatile uint32_t *)0xe000ed34u)
#define SCB_BFAR (*(volatile uint32_t *)0xe000ed38u)
#define SCB_ICSR (*(volatile uint32_t *)0xe000ed04u)

__attribute__((noreturn, used)) void mcu_fault_c(const uint32_t *frame) {
  out_flush();
  out_str("legsim mcu: fault, exception ");
  out_uint(SCB_ICSR & 0x1ffu);
  out_str(" CFSR=");
  out_hex(SCB_CFSR);
  out_str(" HFSR=");
  out_hex(SCB_HFSR);
  out_str(" MMFAR=");
  out_hex(SCB_MMFAR);
  out_str(" BFAR=");
  out_hex(SCB_BFAR);
  out_str(" PC=");
  out_hex(frame[6]);
  out_str(" LR=");
  out_hex(frame[5]);
  out_char('\n');
  semihost_exit(MCU_EXIT_FAULT);
}

/* Hands the stacked exception frame (MSP or PSP) to mcu_fault_c. */
__attribute__((naked, noreturn)) void Fault_Handler(void) {
  __asm__ volatile(
      "tst lr, #4\n"
      "ite eq\n"
      "mrseq r0, msp\n"
      "mrsne r0, psp\n"
      "b mcu_fault_c\n");
}

__attribute__((noreturn)) static void Unexpected_Handler(void) {
  out_flush();
  out_str("legsim mcu: unexpected exception ");
  out_uint(SCB_ICSR & 0x1ffu);
  out_char('\n');
  semihost_exit(MCU_EXIT_FAULT);
}

/* Vector table at the start of flash (VTOR = 0 after reset). The images enable
 * no interrupt; every IRQ slot reports itself. 16 system + 48 external entries. */
typedef void (*vector_t)(void);
__attribute__((section(".isr_vector"), used)) const vector_t mcu_vectors[16 + 48] = {
    (vector_t)(uintptr_t)__stack_top__, /* initial MSP */
    Reset_Handler,
    Unexpected_Handler, /* NMI */
    Fault_Handler,      /* HardFault */
    Fault_Handler,      /* MemManage */
    Fault_Handler,      /* BusFault */
    Fault_Handler,      /* UsageFault */
    0, 0, 0, 0,
    Unexpected_Handler, /* SVCall */
    Unexpected_Handler, /* DebugMonitor */
    0,
    Unexpected_Handler, /* PendSV */
    Unexpected_Handler, /* SysTick */
    [16 ... 63] = Unexpected_Handler,
};
