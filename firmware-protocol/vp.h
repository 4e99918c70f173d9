/* vitreo device protocol (VP), version 1.1 — freestanding C99.
 *
 * The same file builds for the rig's microcontrollers (Cortex-M, -ffreestanding) and for the host.
 * No heap, no libc beyond memcpy/memset, no floating-point maths beyond comparisons (so no libm).
 * The byte layouts, units, ranges and CAN ID allocation are specified in PROTOCOL.md beside this
 * file; the names below carry their units (_us, _mm, _hz).
 */
#ifndef VITREO_FIRMWARE_PROTOCOL_VP_H
#define VITREO_FIRMWARE_PROTOCOL_VP_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define VP_PROTO_MAJOR 1u
#define VP_PROTO_MINOR 1u

#define VP_HEADER_SIZE 4u   /* version, type, sequence, payload length */
#define VP_MAX_PAYLOAD 56u  /* so a packet plus CRC fits a 64-byte USB packet / CAN FD frame */
#define VP_MAX_PACKET (VP_HEADER_SIZE + VP_MAX_PAYLOAD)
#define VP_CRC_SIZE 2u         /* CRC-16: USB transfers and multi-frame CAN transfers */
#define VP_SERIAL_CRC_SIZE 4u  /* CRC-32C: serial frames (no lower layer checks a UART) */
/* serial frame: COBS(packet + CRC) adds at most one byte per 254, plus the 0x00 delimiter */
#define VP_SERIAL_MAX_FRAME (VP_MAX_PACKET + VP_SERIAL_CRC_SIZE + 2u)
#define VP_USB_MAX_PACKET (VP_MAX_PACKET + VP_CRC_SIZE)
#define VP_CANFD_MAX_DATA 64u
#define VP_CAN_MAX_SEGMENTS 10u /* ceil((60 + 2) / 7) */

#define VP_MAX_PEDAL_AXES 4u
#define VP_MAX_EYE_PORTS 4u

/* Results. Negative values are errors; every decoder reports one of these instead of guessing. */
typedef enum {
  VP_OK = 0,
  VP_NEED_MORE = 1,         /* stream/reassembly decoders: frame not complete yet */
  VP_ERR_TRUNCATED = -1,    /* fewer bytes than the header or the declared payload length */
  VP_ERR_CRC = -2,          /* CRC mismatch */
  VP_ERR_VERSION = -3,      /* protocol major version other than VP_PROTO_MAJOR */
  VP_ERR_UNKNOWN_TYPE = -4, /* message type not defined in this version */
  VP_ERR_LENGTH = -5,       /* payload length wrong for the message type */
  VP_ERR_RANGE = -6,        /* a field is NaN/infinite or outside its documented range */
  VP_ERR_FRAMING = -7,      /* COBS violation, bad CAN ID, CAN ID/type mismatch */
  VP_ERR_OVERFLOW = -8,     /* frame longer than the largest legal frame (lost delimiter) */
  VP_ERR_SEQUENCE = -9,     /* CAN segmentation: missing start, toggle error, transfer id change */
  VP_ERR_ARG = -10          /* caller error: buffer too small, null pointer */
} vp_status;

typedef enum {
  VP_MSG_HEARTBEAT = 0x01,
  VP_MSG_DEVICE_INFO = 0x02,
  VP_MSG_TIME_SYNC = 0x03,
  VP_MSG_STATUS = 0x04,
  VP_MSG_CONFIG = 0x05,
  VP_MSG_CALIB_REQUEST = 0x06,
  VP_MSG_CALIB_RESULT = 0x07,
  VP_MSG_POSE_SAMPLE = 0x10,
  VP_MSG_PEDAL_STATE = 0x11,
  VP_MSG_EYEBALL_STATE = 0x12
} vp_msg_type;

typedef enum {
  VP_DEVICE_HOST = 0,
  VP_DEVICE_TRACKER = 1,
  VP_DEVICE_PEDAL = 2,
  VP_DEVICE_EYEBALL = 3
} vp_device_type;

typedef enum {
  VP_TOOL_NONE = 0, VP_TOOL_LIGHT_PIPE = 1, VP_TOOL_VITRECTOR = 2, VP_TOOL_FORCEPS = 3,
  VP_TOOL_SCISSORS = 4, VP_TOOL_LASER = 5, VP_TOOL_PICK = 6, VP_TOOL_FLUTE = 7,
  VP_TOOL_INFUSION = 8, VP_TOOL_BLADE = 9, VP_TOOL_SIDEWAYS_BLADE = 10, /* 1.1 */
  VP_TOOL_COUNT = 11
} vp_tool_type;

typedef enum { VP_CFG_GET = 0, VP_CFG_SET = 1, VP_CFG_ACK = 2, VP_CFG_NAK = 3 } vp_config_op;
typedef enum {
  VP_CFG_KEY_IDENTIFY = 0,        /* GET: device answers with DEVICE_INFO */
  VP_CFG_KEY_SAMPLE_RATE_HZ = 1,  /* SET: stream rate; ACK carries the rate in effect */
  VP_CFG_KEY_STREAMING = 2        /* SET 1/0: start/stop sample streaming */
} vp_config_key;

typedef struct {
  uint64_t uptime_us;
  uint8_t device_state; /* 0 idle, 1 streaming, 2 error */
  uint16_t error_count;
} vp_heartbeat;

typedef struct {
  uint8_t device_type; /* vp_device_type */
  uint8_t hw_revision;
  uint32_t serial;
  uint8_t fw_major, fw_minor, fw_patch;
  uint8_t proto_major, proto_minor;
  uint16_t sample_rate_hz;
} vp_device_info;

typedef struct {
  uint8_t phase; /* 0 = host request, 1 = device reply */
  uint8_t exchange;
  uint64_t host_tx_us;   /* host clock when the request left */
  uint64_t device_rx_us; /* device clock when the request arrived (reply only) */
  uint64_t device_tx_us; /* device clock when the reply left (reply only) */
} vp_time_sync;

typedef struct {
  uint8_t severity; /* 0 info, 1 warning, 2 error, 3 fatal */
  uint16_t code;
  uint32_t detail;
  uint64_t timestamp_us;
} vp_status_msg;

typedef struct {
  uint8_t op; /* vp_config_op */
  uint16_t key;
  uint32_t value;
} vp_config;

typedef struct {
  uint8_t procedure; /* 0 tip pivot, 1 pedal travel, 2 eye zero */
  uint8_t instrument_id;
  uint16_t token;
} vp_calib_request;

typedef struct {
  uint8_t procedure;
  uint8_t instrument_id;
  uint16_t token;
  uint8_t result; /* 0 ok, 1 failed, 2 aborted */
  float residual_mm;
  float offset_mm[3];
} vp_calib_result;

typedef struct {
  uint64_t timestamp_us; /* device clock, µs */
  uint8_t instrument_id;
  uint8_t tool_type; /* vp_tool_type */
  float tip_mm[3];   /* tracker frame, mm */
  float q_wxyz[4];   /* unit quaternion, tracker frame → instrument */
  uint16_t actuation; /* 0 = open/released .. 65535 = fully closed */
  uint8_t quality_pct;
} vp_pose_sample;

typedef struct {
  uint64_t timestamp_us;
  uint8_t pedal_id; /* 0 vitrectomy pedal, 1 microscope pedal */
  uint8_t axis_count;
  uint16_t axes[VP_MAX_PEDAL_AXES]; /* 0..65535 = 0..1 of travel; unused axes are 0 */
  uint16_t switches;                /* bit mask */
} vp_pedal_state;

typedef struct {
  uint8_t flags; /* bit 0: instrument inserted */
  float depth_mm;
} vp_eye_port;

typedef struct {
  uint64_t timestamp_us;
  float q_wxyz[4];
  uint8_t port_count;
  vp_eye_port ports[VP_MAX_EYE_PORTS];
} vp_eyeball_state;

typedef struct {
  uint8_t type;          /* vp_msg_type */
  uint8_t version_minor; /* minor version the sender declared */
  uint8_t seq;           /* wraps at 256; the receiver counts gaps as drops */
  union {
    vp_heartbeat heartbeat;
    vp_device_info device_info;
    vp_time_sync time_sync;
    vp_status_msg status;
    vp_config config;
    vp_calib_request calib_request;
    vp_calib_result calib_result;
    vp_pose_sample pose;
    vp_pedal_state pedal;
    vp_eyeball_state eyeball;
  } u;
} vp_message;

/* ---- packets (transport independent) ----------------------------------------------------------- */
/* Payload length of a message type in this version; 0 for an unknown type. */
size_t vp_payload_size(uint8_t type);
/* Encodes header + payload. Encoders do not validate ranges (simulators must be able to send bad
 * values on purpose); decoders do. */
vp_status vp_encode_packet(const vp_message* m, uint8_t* out, size_t cap, size_t* out_len);
/* Decodes and validates one packet of exactly `len` bytes. */
vp_status vp_decode_packet(const uint8_t* in, size_t len, vp_message* out);
/* Range checks alone (used by decode; exposed for firmware self-checks). */
vp_status vp_validate(const vp_message* m);
const char* vp_status_name(int status);
const char* vp_msg_type_name(uint8_t type);

/* ---- CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection); check("123456789") = 0x29B1 */
uint16_t vp_crc16(const uint8_t* data, size_t len);
uint16_t vp_crc16_update(uint16_t crc, const uint8_t* data, size_t len);

/* ---- CRC-32C (Castagnoli; reflected poly 0x82F63B78, init/xorout 0xFFFFFFFF); check = 0xE3069283 */
uint32_t vp_crc32c(const uint8_t* data, size_t len);

/* ---- COBS (Cheshire & Baker 1999) --------------------------------------------------------------- */
/* Returns encoded length (no delimiter), 0 if cap is too small. */
size_t vp_cobs_encode(const uint8_t* in, size_t len, uint8_t* out, size_t cap);
/* Decodes a frame without its delimiter. Returns decoded length or a negative vp_status. */
int vp_cobs_decode(const uint8_t* in, size_t len, uint8_t* out, size_t cap);

/* ---- serial: COBS(packet || CRC32C big-endian) || 0x00 ------------------------------------------ */
vp_status vp_serial_encode(const vp_message* m, uint8_t* out, size_t cap, size_t* out_len);

typedef struct {
  uint8_t buf[VP_SERIAL_MAX_FRAME];
  size_t len; /* bytes of the current frame so far */
  uint8_t discarding; /* after an overflow: drop bytes up to the next delimiter */
} vp_serial_rx;

void vp_serial_rx_init(vp_serial_rx* rx);
/* Feeds bytes. Stops after the first completed frame: returns VP_OK (message in *out), a negative
 * status (frame rejected), or VP_NEED_MORE when all bytes were consumed without a complete frame.
 * *consumed says how many bytes were taken; call again with the rest. */
int vp_serial_rx_push(vp_serial_rx* rx, const uint8_t* data, size_t len, size_t* consumed,
                      vp_message* out);
/* Decodes one complete frame body (between delimiters, without them). */
vp_status vp_serial_decode_frame(const uint8_t* frame, size_t len, vp_message* out);

/* ---- USB: one packet || CRC16 per interrupt/bulk transfer (max 62 bytes) ----------------------- */
vp_status vp_usb_encode(const vp_message* m, uint8_t* out, size_t cap, size_t* out_len);
vp_status vp_usb_decode(const uint8_t* in, size_t len, vp_message* out);

/* ---- CAN ---------------------------------------------------------------------------------------- */
/* 29-bit extended ID: [28:26] priority, [25:18] message type, [17] direction (1 = host to device),
 * [16:7] reserved 0, [6:0] node id (the sender's; for host-to-device frames the addressee's). */
#define VP_CAN_ID_TO_DEVICE (1uL << 17)
uint32_t vp_can_id(uint8_t priority, uint8_t type, uint8_t node_id);
uint8_t vp_can_default_priority(uint8_t type);
vp_status vp_can_parse_id(uint32_t can_id, uint8_t* priority, uint8_t* type, uint8_t* node_id);

/* CAN FD single frame: the packet, zero-padded to the next valid FD length. */
vp_status vp_canfd_encode(const vp_message* m, uint8_t node_id, uint32_t* can_id, uint8_t* data,
                          size_t* data_len);
vp_status vp_canfd_decode(uint32_t can_id, const uint8_t* data, size_t len, uint8_t* node_id,
                          vp_message* out);
size_t vp_canfd_round_len(size_t len);

/* Classic CAN (8 bytes): 7 data bytes + tail byte [SOT EOT TOGGLE TID4..0] per frame (the tail
 * byte idea is Cyphal/CAN's). Multi-frame transfers append CRC16 over the packet. */
#define VP_CAN_TAIL_SOT 0x80u
#define VP_CAN_TAIL_EOT 0x40u
#define VP_CAN_TAIL_TOGGLE 0x20u
typedef struct {
  uint8_t data[8];
  uint8_t len;
} vp_can_frame8;
vp_status vp_can_segment(const vp_message* m, uint8_t node_id, uint8_t transfer_id,
                         uint32_t* can_id, vp_can_frame8* frames, size_t max_frames,
                         size_t* frame_count);

#define VP_CAN_RX_SLOTS 8u
typedef struct {
  uint32_t can_id;
  uint8_t active;
  uint8_t transfer_id;
  uint8_t toggle;
  uint8_t len;
  uint8_t buf[VP_MAX_PACKET + VP_CRC_SIZE + 7u];
} vp_can_rx_slot;
typedef struct {
  vp_can_rx_slot slots[VP_CAN_RX_SLOTS];
} vp_can_rx;
void vp_can_rx_init(vp_can_rx* rx);
/* Feeds one classic frame. VP_OK: a transfer completed (message + node id out); VP_NEED_MORE: a
 * segment was stored; negative: the frame/transfer was rejected (the slot is reset). */
int vp_can_rx_push(vp_can_rx* rx, uint32_t can_id, const uint8_t* data, size_t len,
                   uint8_t* node_id, vp_message* out);

#ifdef __cplusplus
}
#endif
#endif
