/* libFuzzer targets, one per decoder, selected by -DVP_FUZZ_<NAME>. Beyond "no crash, no sanitizer
 * report", each asserts that whatever a decoder accepts re-encodes to the bytes it came from: a
 * decoder that accepted something it then described differently would be misparsing. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "firmware-protocol/vp.h"

#if defined(VP_FUZZ_PACKET) || defined(VP_FUZZ_USB) || defined(VP_FUZZ_CANFD)
static void check_reencodes(const vp_message* m, const uint8_t* packet, size_t len) {
  uint8_t again[VP_MAX_PACKET];
  size_t n = 0;
  if (vp_encode_packet(m, again, sizeof again, &n) != VP_OK) abort();
  /* a newer minor may carry trailing fields we drop; the known prefix must match */
  if ((packet[0] & 0x0F) <= VP_PROTO_MINOR && (n != len || memcmp(again + 1, packet + 1, n - 1) != 0)) abort();
  if (vp_validate(m) != VP_OK) abort();
}
#endif

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  vp_message m;
#if defined(VP_FUZZ_PACKET)
  if (vp_decode_packet(data, size, &m) == VP_OK) check_reencodes(&m, data, size);
#elif defined(VP_FUZZ_SERIAL)
  vp_serial_rx rx;
  size_t used = 0;
  vp_serial_rx_init(&rx);
  while (size > 0) {
    int st = vp_serial_rx_push(&rx, data, size, &used, &m);
    if (used == 0 || used > size) abort(); /* must always make progress */
    if (st == VP_OK && vp_validate(&m) != VP_OK) abort();
    data += used;
    size -= used;
  }
#elif defined(VP_FUZZ_USB)
  if (vp_usb_decode(data, size, &m) == VP_OK) check_reencodes(&m, data, size - 2);
#elif defined(VP_FUZZ_CANFD)
  if (size >= 4) {
    uint32_t id = (uint32_t)data[0] << 24 | (uint32_t)data[1] << 16 | (uint32_t)data[2] << 8 | data[3];
    uint8_t node;
    if (vp_canfd_decode(id, data + 4, size - 4, &node, &m) == VP_OK) check_reencodes(&m, data + 4, 4u + data[7]);
  }
#elif defined(VP_FUZZ_CAN8)
  /* input = sequence of [id:4][len:1][bytes...] records fed to one reassembler */
  vp_can_rx rx;
  vp_can_rx_init(&rx);
  while (size >= 5) {
    uint32_t id = (uint32_t)data[0] << 24 | (uint32_t)data[1] << 16 | (uint32_t)data[2] << 8 | data[3];
    size_t n = data[4] % 9u;
    uint8_t node;
    data += 5;
    size -= 5;
    if (n > size) n = size;
    if (vp_can_rx_push(&rx, id, data, n, &node, &m) == VP_OK && vp_validate(&m) != VP_OK) abort();
    data += n;
    size -= n;
  }
#else
#error "define one VP_FUZZ_* target"
#endif
  return 0;
}
