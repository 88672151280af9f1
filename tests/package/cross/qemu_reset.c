/* Reset vector for running the consumer on QEMU's MPS2 boards (package_cross_* tests):
 * turns the FPU on, then enters newlib's rdimon crt0 (_start), which sets up the stack
 * and heap through semihosting, runs main and exits with its status. Linked with
 * --specs=rdimon.specs -Wl,--section-start=.vectors=0 (the rest where newlib's default
 * linker script puts it: the boards have RAM from address 0). */
extern void _start(void);

static void reset(void) {
  *(volatile unsigned *)0xE000ED88u |= 0xFu << 20; /* CPACR: CP10 and CP11 full access */
  __asm__ volatile("dsb\n\tisb");
  _start();
}

/* initial stack pointer (rdimon's crt0 moves it), reset handler */
__attribute__((section(".vectors"), used)) const void *const qemu_vectors[2] = {
    (void *)0x00400000u, (void *)reset};
