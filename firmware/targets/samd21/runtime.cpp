// The few C++ run-time hooks a freestanding image still references, defined so that nothing of
// the hosted library (heap, exit handling, exceptions) is linked:
//  - operator delete: named by the deleting destructors of classes with virtual destructors
//    (the HAL interfaces). Nothing is ever deleted: no heap exists.
//  - __cxa_pure_virtual: the slot of a pure virtual function; reaching it is a bug.
//  - __aeabi_atexit / __dso_handle: static objects register their destructors; the firmware
//    never exits, so registration is a no-op.
// The two traps reset the chip, as any unexpected interrupt does (startup.cpp).
#include <stddef.h>

extern "C" void unexpected_interrupt();

void operator delete(void*) noexcept { unexpected_interrupt(); }
void operator delete(void*, size_t) noexcept { unexpected_interrupt(); }

extern "C" {

void __cxa_pure_virtual() { unexpected_interrupt(); }

void* __dso_handle = nullptr;

int __aeabi_atexit(void*, void (*)(void*), void*) { return 0; }

}  // extern "C"
