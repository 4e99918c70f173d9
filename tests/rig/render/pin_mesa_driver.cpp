// Keeps Mesa's software DRI driver loaded for the whole test process.
//
// eglTerminate unloads the driver (dlclose); a few allocations Mesa/LLVM make once per process are
// then unreachable and LeakSanitizer reports them (240 bytes, "<unknown module>" frames that no
// suppression file could name). With the driver pinned they stay reachable through its globals, so
// the ASan runs need no suppressions at all, and any leak of ours still fails.
#include <dlfcn.h>

#include <initializer_list>

namespace {
struct PinMesaDriver {
  PinMesaDriver() {
    for (const char* path : {"/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so", "swrast_dri.so"}) {
      if (dlopen(path, RTLD_LAZY | RTLD_GLOBAL) != nullptr) break;  // deliberately never closed
    }
  }
} pin;
}  // namespace

#if defined(__SANITIZE_THREAD__)
// ThreadSanitizer reports races inside llvmpipe (its fence mutex/condvar torn down while its own
// rasteriser thread last touched them through uninstrumented code). Suppress Mesa's software driver
// only; races with a vitreo frame on both sides are still reported.
extern "C" const char* __tsan_default_suppressions() { return "race:swrast_dri.so\n"; }
#endif
