// Semihosting output and exit (startup.cpp).
#pragma once

void semihost_write(const char* text);
[[noreturn]] void semihost_exit(bool ok);
