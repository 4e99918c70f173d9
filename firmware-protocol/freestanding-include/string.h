/* The only libc the protocol may use. The freestanding build puts this directory first on the
 * include path instead of the hosted libc headers, so any other libc call fails to compile. */
#ifndef VITREO_FREESTANDING_STRING_H
#define VITREO_FREESTANDING_STRING_H
#include <stddef.h>
void* memcpy(void* dst, const void* src, size_t n);
void* memset(void* dst, int c, size_t n);
#endif
