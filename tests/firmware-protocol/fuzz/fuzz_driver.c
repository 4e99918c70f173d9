/* Stand-in for libFuzzer where clang is absent: deterministic random inputs (xorshift), mutated
 * from the seed vectors given on the command line, for a fixed number of iterations. Not coverage
 * guided — the clang build is the real fuzzer; this keeps the harness compiled and exercised. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

static uint64_t xorshift_state = 88172645463325252ull;
static uint64_t xorshift_next(void) {
  xorshift_state ^= xorshift_state << 13;
  xorshift_state ^= xorshift_state >> 7;
  xorshift_state ^= xorshift_state << 17;
  return xorshift_state;
}

int main(int argc, char** argv) {
  uint8_t seeds[64][128];
  size_t seed_len[64], nseeds = 0, i;
  long iters = 300000;
  for (i = 1; i < (size_t)argc; ++i) {
    if (strncmp(argv[i], "-runs=", 6) == 0) {
      iters = atol(argv[i] + 6);
      continue;
    }
    FILE* f = fopen(argv[i], "rb");
    if (f && nseeds < 64) {
      seed_len[nseeds] = fread(seeds[nseeds], 1, sizeof seeds[0], f);
      ++nseeds;
    }
    if (f) fclose(f);
  }
  for (long it = 0; it < iters; ++it) {
    uint8_t buf[160];
    size_t n;
    if (nseeds && (it & 1)) {
      size_t k = (size_t)(xorshift_next() % nseeds), flips = 1 + xorshift_next() % 4, j;
      n = seed_len[k];
      memcpy(buf, seeds[k], n);
      for (j = 0; j < flips && n; ++j) buf[xorshift_next() % n] ^= (uint8_t)(1u << (xorshift_next() % 8));
      if (xorshift_next() % 8 == 0 && n) n = (size_t)(xorshift_next() % n);
    } else {
      n = (size_t)(xorshift_next() % sizeof buf);
      for (i = 0; i < n; ++i) buf[i] = (uint8_t)xorshift_next();
    }
    LLVMFuzzerTestOneInput(buf, n);
  }
  printf("ran %ld inputs (deterministic driver, no libFuzzer)\n", iters);
  return 0;
}
