/* The images link with -Wl,--wrap=<fn> for every heap entry point (see
 * CMakeLists.txt, LEGSIM_MCU_HEAP_SYMBOLS): any call that reaches one lands here,
 * reports which one and stops QEMU with MCU_EXIT_HEAP. Nothing in the firmware
 * calls them, so --gc-sections drops these wrappers and the image's symbol table
 * names neither the heap functions nor these __wrap_ stubs (the MCU tests check
 * that). */
#include <stddef.h>

#include "mcu_runtime.h"
#include "out.h"
#include "semihost.h"

__attribute__((noreturn)) static void heap_trap(const char *what) {
  out_flush();
  out_str("legsim mcu: heap call trapped: ");
  out_str(what);
  out_char('\n');
  semihost_exit(MCU_EXIT_HEAP);
}

#define TRAP(sym) \
  __attribute__((noreturn)) void __wrap_##sym(void) { heap_trap(#sym); }

/* C */
TRAP(malloc)
TRAP(free)
TRAP(calloc)
TRAP(realloc)
TRAP(reallocarray)
TRAP(memalign)
TRAP(aligned_alloc)
TRAP(posix_memalign)
TRAP(valloc)
TRAP(pvalloc)
/* newlib's reentrant forms (stdio and friends call these directly) */
TRAP(_malloc_r)
TRAP(_free_r)
TRAP(_calloc_r)
TRAP(_realloc_r)
TRAP(_memalign_r)
/* C++ operator new / delete (32-bit size_t: 'j') */
TRAP(_Znwj)
TRAP(_Znaj)
TRAP(_ZnwjRKSt9nothrow_t)
TRAP(_ZnajRKSt9nothrow_t)
TRAP(_ZnwjSt11align_val_t)
TRAP(_ZnajSt11align_val_t)
TRAP(_ZnwjSt11align_val_tRKSt9nothrow_t)
TRAP(_ZnajSt11align_val_tRKSt9nothrow_t)
TRAP(_ZdlPv)
TRAP(_ZdaPv)
TRAP(_ZdlPvj)
TRAP(_ZdaPvj)
TRAP(_ZdlPvRKSt9nothrow_t)
TRAP(_ZdaPvRKSt9nothrow_t)
TRAP(_ZdlPvSt11align_val_t)
TRAP(_ZdaPvSt11align_val_t)
TRAP(_ZdlPvjSt11align_val_t)
TRAP(_ZdaPvjSt11align_val_t)
TRAP(_ZdlPvSt11align_val_tRKSt9nothrow_t)
TRAP(_ZdaPvSt11align_val_tRKSt9nothrow_t)
/* exception objects */
TRAP(__cxa_allocate_exception)
TRAP(__cxa_free_exception)
TRAP(__cxa_allocate_dependent_exception)
TRAP(__cxa_free_dependent_exception)
