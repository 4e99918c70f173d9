/* VP message codec: header + payload, little-endian, with range validation on decode.
 * Layouts are the tables of PROTOCOL.md; keep the two in step. */
#include "vp.h"

#include <string.h>

/* ---- little-endian primitives: explicit byte order, no alignment assumptions (Cortex-M0 faults
 * on unaligned access, and the host must not depend on its own endianness) ---- */
static void put_u16(uint8_t* p, uint16_t v) {
  p[0] = (uint8_t)v;
  p[1] = (uint8_t)(v >> 8);
}
static void put_u32(uint8_t* p, uint32_t v) {
  p[0] = (uint8_t)v;
  p[1] = (uint8_t)(v >> 8);
  p[2] = (uint8_t)(v >> 16);
  p[3] = (uint8_t)(v >> 24);
}
static void put_u64(uint8_t* p, uint64_t v) {
  put_u32(p, (uint32_t)v);
  put_u32(p + 4, (uint32_t)(v >> 32));
}
static void put_f32(uint8_t* p, float f) {
  uint32_t v;
  memcpy(&v, &f, 4);
  put_u32(p, v);
}
static uint16_t get_u16(const uint8_t* p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static uint32_t get_u32(const uint8_t* p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static uint64_t get_u64(const uint8_t* p) { return (uint64_t)get_u32(p) | ((uint64_t)get_u32(p + 4) << 32); }
static float get_f32(const uint8_t* p) {
  uint32_t v = get_u32(p);
  float f;
  memcpy(&f, &v, 4);
  return f;
}

/* Payload sizes of protocol 1.0 (PROTOCOL.md, "Messages"). */
#define SZ_HEARTBEAT 11u
#define SZ_DEVICE_INFO 13u
#define SZ_TIME_SYNC 26u
#define SZ_STATUS 15u
#define SZ_CONFIG 7u
#define SZ_CALIB_REQUEST 4u
#define SZ_CALIB_RESULT 21u
#define SZ_POSE 41u
#define SZ_PEDAL 20u
#define SZ_EYEBALL 45u

/* Cyphal's habit: prove at compile time that every message fits its smallest frame. */
typedef char vp_assert_pose_fits[(VP_HEADER_SIZE + SZ_POSE + VP_CRC_SIZE <= 64u) ? 1 : -1];
typedef char vp_assert_eye_fits[(SZ_EYEBALL <= VP_MAX_PAYLOAD) ? 1 : -1];

size_t vp_payload_size(uint8_t type) {
  switch (type) {
    case VP_MSG_HEARTBEAT: return SZ_HEARTBEAT;
    case VP_MSG_DEVICE_INFO: return SZ_DEVICE_INFO;
    case VP_MSG_TIME_SYNC: return SZ_TIME_SYNC;
    case VP_MSG_STATUS: return SZ_STATUS;
    case VP_MSG_CONFIG: return SZ_CONFIG;
    case VP_MSG_CALIB_REQUEST: return SZ_CALIB_REQUEST;
    case VP_MSG_CALIB_RESULT: return SZ_CALIB_RESULT;
    case VP_MSG_POSE_SAMPLE: return SZ_POSE;
    case VP_MSG_PEDAL_STATE: return SZ_PEDAL;
    case VP_MSG_EYEBALL_STATE: return SZ_EYEBALL;
    default: return 0;
  }
}

vp_status vp_encode_packet(const vp_message* m, uint8_t* out, size_t cap, size_t* out_len) {
  size_t n;
  uint8_t* p;
  unsigned i;
  if (!m || !out || !out_len) return VP_ERR_ARG;
  n = vp_payload_size(m->type);
  if (n == 0) return VP_ERR_UNKNOWN_TYPE;
  if (cap < VP_HEADER_SIZE + n) return VP_ERR_ARG;
  out[0] = (uint8_t)((VP_PROTO_MAJOR << 4) | (m->version_minor & 0x0Fu));
  out[1] = m->type;
  out[2] = m->seq;
  out[3] = (uint8_t)n;
  p = out + VP_HEADER_SIZE;
  memset(p, 0, n);
  switch (m->type) {
    case VP_MSG_HEARTBEAT:
      put_u64(p, m->u.heartbeat.uptime_us);
      p[8] = m->u.heartbeat.device_state;
      put_u16(p + 9, m->u.heartbeat.error_count);
      break;
    case VP_MSG_DEVICE_INFO: {
      const vp_device_info* d = &m->u.device_info;
      p[0] = d->device_type;
      p[1] = d->hw_revision;
      put_u32(p + 2, d->serial);
      p[6] = d->fw_major;
      p[7] = d->fw_minor;
      p[8] = d->fw_patch;
      p[9] = d->proto_major;
      p[10] = d->proto_minor;
      put_u16(p + 11, d->sample_rate_hz);
      break;
    }
    case VP_MSG_TIME_SYNC:
      p[0] = m->u.time_sync.phase;
      p[1] = m->u.time_sync.exchange;
      put_u64(p + 2, m->u.time_sync.host_tx_us);
      put_u64(p + 10, m->u.time_sync.device_rx_us);
      put_u64(p + 18, m->u.time_sync.device_tx_us);
      break;
    case VP_MSG_STATUS:
      p[0] = m->u.status.severity;
      put_u16(p + 1, m->u.status.code);
      put_u32(p + 3, m->u.status.detail);
      put_u64(p + 7, m->u.status.timestamp_us);
      break;
    case VP_MSG_CONFIG:
      p[0] = m->u.config.op;
      put_u16(p + 1, m->u.config.key);
      put_u32(p + 3, m->u.config.value);
      break;
    case VP_MSG_CALIB_REQUEST:
      p[0] = m->u.calib_request.procedure;
      p[1] = m->u.calib_request.instrument_id;
      put_u16(p + 2, m->u.calib_request.token);
      break;
    case VP_MSG_CALIB_RESULT:
      p[0] = m->u.calib_result.procedure;
      p[1] = m->u.calib_result.instrument_id;
      put_u16(p + 2, m->u.calib_result.token);
      p[4] = m->u.calib_result.result;
      put_f32(p + 5, m->u.calib_result.residual_mm);
      for (i = 0; i < 3; ++i) put_f32(p + 9 + 4 * i, m->u.calib_result.offset_mm[i]);
      break;
    case VP_MSG_POSE_SAMPLE: {
      const vp_pose_sample* s = &m->u.pose;
      put_u64(p, s->timestamp_us);
      p[8] = s->instrument_id;
      p[9] = s->tool_type;
      for (i = 0; i < 3; ++i) put_f32(p + 10 + 4 * i, s->tip_mm[i]);
      for (i = 0; i < 4; ++i) put_f32(p + 22 + 4 * i, s->q_wxyz[i]);
      put_u16(p + 38, s->actuation);
      p[40] = s->quality_pct;
      break;
    }
    case VP_MSG_PEDAL_STATE: {
      const vp_pedal_state* s = &m->u.pedal;
      put_u64(p, s->timestamp_us);
      p[8] = s->pedal_id;
      p[9] = s->axis_count;
      for (i = 0; i < VP_MAX_PEDAL_AXES; ++i) put_u16(p + 10 + 2 * i, s->axes[i]);
      put_u16(p + 18, s->switches);
      break;
    }
    case VP_MSG_EYEBALL_STATE: {
      const vp_eyeball_state* s = &m->u.eyeball;
      put_u64(p, s->timestamp_us);
      for (i = 0; i < 4; ++i) put_f32(p + 8 + 4 * i, s->q_wxyz[i]);
      p[24] = s->port_count;
      for (i = 0; i < VP_MAX_EYE_PORTS; ++i) {
        p[25 + 5 * i] = s->ports[i].flags;
        put_f32(p + 26 + 5 * i, s->ports[i].depth_mm);
      }
      break;
    }
    default: return VP_ERR_UNKNOWN_TYPE;
  }
  *out_len = VP_HEADER_SIZE + n;
  return VP_OK;
}

/* Comparisons are false for NaN, and ±inf falls outside every finite range, so one test covers
 * NaN, infinity and out-of-range without libm. */
static int in_range(float x, float lo, float hi) { return x >= lo && x <= hi; }

static int unit_quaternion(const float q[4]) {
  float n2;
  unsigned i;
  for (i = 0; i < 4; ++i)
    if (!in_range(q[i], -1.01f, 1.01f)) return 0;
  n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  /* firmware normalises before sending; 2 % on |q|² allows float16-era sensors' rounding */
  return in_range(n2, 0.98f, 1.02f);
}

#define VP_TIP_LIMIT_MM 500.0f /* tracker working volume: ±0.5 m around its origin */
#define VP_PORT_DEPTH_MAX_MM 40.0f

vp_status vp_validate(const vp_message* m) {
  unsigned i;
  if (!m) return VP_ERR_ARG;
  switch (m->type) {
    case VP_MSG_HEARTBEAT: return m->u.heartbeat.device_state <= 2 ? VP_OK : VP_ERR_RANGE;
    case VP_MSG_DEVICE_INFO:
      return (m->u.device_info.device_type >= 1 && m->u.device_info.device_type <= 3) ? VP_OK
                                                                                       : VP_ERR_RANGE;
    case VP_MSG_TIME_SYNC: return m->u.time_sync.phase <= 1 ? VP_OK : VP_ERR_RANGE;
    case VP_MSG_STATUS: return m->u.status.severity <= 3 ? VP_OK : VP_ERR_RANGE;
    case VP_MSG_CONFIG: return m->u.config.op <= 3 ? VP_OK : VP_ERR_RANGE;
    case VP_MSG_CALIB_REQUEST: return m->u.calib_request.procedure <= 2 ? VP_OK : VP_ERR_RANGE;
    case VP_MSG_CALIB_RESULT: {
      const vp_calib_result* r = &m->u.calib_result;
      if (r->procedure > 2 || r->result > 2) return VP_ERR_RANGE;
      if (!in_range(r->residual_mm, 0.0f, 1000.0f)) return VP_ERR_RANGE;
      for (i = 0; i < 3; ++i)
        if (!in_range(r->offset_mm[i], -VP_TIP_LIMIT_MM, VP_TIP_LIMIT_MM)) return VP_ERR_RANGE;
      return VP_OK;
    }
    case VP_MSG_POSE_SAMPLE: {
      const vp_pose_sample* s = &m->u.pose;
      if (s->tool_type >= VP_TOOL_COUNT || s->quality_pct > 100) return VP_ERR_RANGE;
      for (i = 0; i < 3; ++i)
        if (!in_range(s->tip_mm[i], -VP_TIP_LIMIT_MM, VP_TIP_LIMIT_MM)) return VP_ERR_RANGE;
      return unit_quaternion(s->q_wxyz) ? VP_OK : VP_ERR_RANGE;
    }
    case VP_MSG_PEDAL_STATE: {
      const vp_pedal_state* s = &m->u.pedal;
      if (s->pedal_id > 1 || s->axis_count > VP_MAX_PEDAL_AXES) return VP_ERR_RANGE;
      for (i = s->axis_count; i < VP_MAX_PEDAL_AXES; ++i)
        if (s->axes[i] != 0) return VP_ERR_RANGE;
      return VP_OK;
    }
    case VP_MSG_EYEBALL_STATE: {
      const vp_eyeball_state* s = &m->u.eyeball;
      if (s->port_count > VP_MAX_EYE_PORTS || !unit_quaternion(s->q_wxyz)) return VP_ERR_RANGE;
      for (i = 0; i < VP_MAX_EYE_PORTS; ++i) {
        const vp_eye_port* pt = &s->ports[i];
        if (pt->flags & ~1u) return VP_ERR_RANGE;
        if (!in_range(pt->depth_mm, 0.0f, VP_PORT_DEPTH_MAX_MM)) return VP_ERR_RANGE;
        /* unused ports and withdrawn instruments report exactly zero depth */
        if ((i >= s->port_count || !(pt->flags & 1u)) && (pt->flags != 0 || pt->depth_mm != 0.0f))
          return VP_ERR_RANGE;
      }
      return VP_OK;
    }
    default: return VP_ERR_UNKNOWN_TYPE;
  }
}

vp_status vp_decode_packet(const uint8_t* in, size_t len, vp_message* out) {
  size_t n, declared;
  const uint8_t* p;
  unsigned i;
  uint8_t major, minor;
  if (!in || !out) return VP_ERR_ARG;
  if (len < VP_HEADER_SIZE) return VP_ERR_TRUNCATED;
  major = (uint8_t)(in[0] >> 4);
  minor = (uint8_t)(in[0] & 0x0Fu);
  /* the version is checked before anything else is interpreted: a different major may have moved
   * every field */
  if (major != VP_PROTO_MAJOR) return VP_ERR_VERSION;
  declared = in[3];
  if (declared > VP_MAX_PAYLOAD) return VP_ERR_LENGTH;
  if (len != VP_HEADER_SIZE + declared) return len < VP_HEADER_SIZE + declared ? VP_ERR_TRUNCATED : VP_ERR_LENGTH;
  n = vp_payload_size(in[1]);
  if (n == 0) return VP_ERR_UNKNOWN_TYPE;
  /* same or older minor: exact size. Newer minor: may append fields, which we ignore. */
  if (minor <= VP_PROTO_MINOR ? declared != n : declared < n) return VP_ERR_LENGTH;
  memset(out, 0, sizeof *out);
  out->type = in[1];
  out->version_minor = minor;
  out->seq = in[2];
  p = in + VP_HEADER_SIZE;
  switch (out->type) {
    case VP_MSG_HEARTBEAT:
      out->u.heartbeat.uptime_us = get_u64(p);
      out->u.heartbeat.device_state = p[8];
      out->u.heartbeat.error_count = get_u16(p + 9);
      break;
    case VP_MSG_DEVICE_INFO: {
      vp_device_info* d = &out->u.device_info;
      d->device_type = p[0];
      d->hw_revision = p[1];
      d->serial = get_u32(p + 2);
      d->fw_major = p[6];
      d->fw_minor = p[7];
      d->fw_patch = p[8];
      d->proto_major = p[9];
      d->proto_minor = p[10];
      d->sample_rate_hz = get_u16(p + 11);
      break;
    }
    case VP_MSG_TIME_SYNC:
      out->u.time_sync.phase = p[0];
      out->u.time_sync.exchange = p[1];
      out->u.time_sync.host_tx_us = get_u64(p + 2);
      out->u.time_sync.device_rx_us = get_u64(p + 10);
      out->u.time_sync.device_tx_us = get_u64(p + 18);
      break;
    case VP_MSG_STATUS:
      out->u.status.severity = p[0];
      out->u.status.code = get_u16(p + 1);
      out->u.status.detail = get_u32(p + 3);
      out->u.status.timestamp_us = get_u64(p + 7);
      break;
    case VP_MSG_CONFIG:
      out->u.config.op = p[0];
      out->u.config.key = get_u16(p + 1);
      out->u.config.value = get_u32(p + 3);
      break;
    case VP_MSG_CALIB_REQUEST:
      out->u.calib_request.procedure = p[0];
      out->u.calib_request.instrument_id = p[1];
      out->u.calib_request.token = get_u16(p + 2);
      break;
    case VP_MSG_CALIB_RESULT:
      out->u.calib_result.procedure = p[0];
      out->u.calib_result.instrument_id = p[1];
      out->u.calib_result.token = get_u16(p + 2);
      out->u.calib_result.result = p[4];
      out->u.calib_result.residual_mm = get_f32(p + 5);
      for (i = 0; i < 3; ++i) out->u.calib_result.offset_mm[i] = get_f32(p + 9 + 4 * i);
      break;
    case VP_MSG_POSE_SAMPLE: {
      vp_pose_sample* s = &out->u.pose;
      s->timestamp_us = get_u64(p);
      s->instrument_id = p[8];
      s->tool_type = p[9];
      for (i = 0; i < 3; ++i) s->tip_mm[i] = get_f32(p + 10 + 4 * i);
      for (i = 0; i < 4; ++i) s->q_wxyz[i] = get_f32(p + 22 + 4 * i);
      s->actuation = get_u16(p + 38);
      s->quality_pct = p[40];
      break;
    }
    case VP_MSG_PEDAL_STATE: {
      vp_pedal_state* s = &out->u.pedal;
      s->timestamp_us = get_u64(p);
      s->pedal_id = p[8];
      s->axis_count = p[9];
      for (i = 0; i < VP_MAX_PEDAL_AXES; ++i) s->axes[i] = get_u16(p + 10 + 2 * i);
      s->switches = get_u16(p + 18);
      break;
    }
    case VP_MSG_EYEBALL_STATE: {
      vp_eyeball_state* s = &out->u.eyeball;
      s->timestamp_us = get_u64(p);
      for (i = 0; i < 4; ++i) s->q_wxyz[i] = get_f32(p + 8 + 4 * i);
      s->port_count = p[24];
      for (i = 0; i < VP_MAX_EYE_PORTS; ++i) {
        s->ports[i].flags = p[25 + 5 * i];
        s->ports[i].depth_mm = get_f32(p + 26 + 5 * i);
      }
      break;
    }
    default: return VP_ERR_UNKNOWN_TYPE;
  }
  return vp_validate(out);
}

const char* vp_status_name(int status) {
  switch (status) {
    case VP_OK: return "ok";
    case VP_NEED_MORE: return "need more bytes";
    case VP_ERR_TRUNCATED: return "truncated";
    case VP_ERR_CRC: return "CRC mismatch";
    case VP_ERR_VERSION: return "unsupported protocol version";
    case VP_ERR_UNKNOWN_TYPE: return "unknown message type";
    case VP_ERR_LENGTH: return "wrong payload length";
    case VP_ERR_RANGE: return "value out of range (NaN/inf/limits)";
    case VP_ERR_FRAMING: return "framing error";
    case VP_ERR_OVERFLOW: return "frame too long";
    case VP_ERR_SEQUENCE: return "segment sequence error";
    case VP_ERR_ARG: return "invalid argument";
    default: return "unknown status";
  }
}

const char* vp_msg_type_name(uint8_t type) {
  switch (type) {
    case VP_MSG_HEARTBEAT: return "heartbeat";
    case VP_MSG_DEVICE_INFO: return "device_info";
    case VP_MSG_TIME_SYNC: return "time_sync";
    case VP_MSG_STATUS: return "status";
    case VP_MSG_CONFIG: return "config";
    case VP_MSG_CALIB_REQUEST: return "calib_request";
    case VP_MSG_CALIB_RESULT: return "calib_result";
    case VP_MSG_POSE_SAMPLE: return "pose_sample";
    case VP_MSG_PEDAL_STATE: return "pedal_state";
    case VP_MSG_EYEBALL_STATE: return "eyeball_state";
    default: return "unknown";
  }
}
