#!/usr/bin/env python3
"""Writes the VP test vectors from PROTOCOL.md alone, independently of the C codec.

This is a second implementation of the byte layouts (struct.pack, a bitwise CRC, a textbook COBS),
so a shared misunderstanding would have to be made twice. Run it from this folder; it rewrites the
*.bin files and vectors.txt. The C and C++ tests then check that the codec decodes every file to the
meaning given in vectors.txt and encodes that meaning back to the same bytes.
"""
import math
import struct

MAJOR, MINOR = 1, 1
T = dict(heartbeat=0x01, device_info=0x02, time_sync=0x03, status=0x04, config=0x05,
         calib_request=0x06, calib_result=0x07, pose_sample=0x10, pedal_state=0x11, eyeball_state=0x12)
PRIO = dict(time_sync=1, pose_sample=2, pedal_state=2, eyeball_state=2, status=3, config=5,
            calib_request=5, calib_result=5)


def f32(x):
    return struct.unpack('<f', struct.pack('<f', x))[0]


def crc16(data):  # CRC-16/CCITT-FALSE, bit by bit
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


assert crc16(b'123456789') == 0x29B1


def crc32c(data):  # CRC-32C (Castagnoli), reflected, bit by bit
    crc = 0xFFFFFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0x82F63B78 if crc & 1 else crc >> 1
    return crc ^ 0xFFFFFFFF


assert crc32c(b'123456789') == 0xE3069283


def cobs(data):
    out, block = bytearray(), bytearray()
    for b in data:
        if b == 0:
            out += bytes([len(block) + 1]) + block
            block = bytearray()
        else:
            block.append(b)
            if len(block) == 254:
                out += bytes([255]) + block
                block = bytearray()
    out += bytes([len(block) + 1]) + block
    return bytes(out)


# payload packers: (struct format, field names) per PROTOCOL.md
LAYOUT = {
    'heartbeat': ('<QBH', ['uptime_us', 'device_state', 'error_count']),
    'device_info': ('<BBIBBBBBH', ['device_type', 'hw_revision', 'serial', 'fw_major', 'fw_minor', 'fw_patch',
                                   'proto_major', 'proto_minor', 'sample_rate_hz']),
    'time_sync': ('<BBQQQ', ['phase', 'exchange', 'host_tx_us', 'device_rx_us', 'device_tx_us']),
    'status': ('<BHIQ', ['severity', 'code', 'detail', 'timestamp_us']),
    'config': ('<BHI', ['op', 'key', 'value']),
    'calib_request': ('<BBH', ['procedure', 'instrument_id', 'token']),
    'calib_result': ('<BBHBf3f', ['procedure', 'instrument_id', 'token', 'result', 'residual_mm', 'offset_mm*3']),
    'pose_sample': ('<QBB3f4fHB', ['timestamp_us', 'instrument_id', 'tool_type', 'tip_mm*3', 'q_wxyz*4',
                                   'actuation', 'quality_pct']),
    'pedal_state': ('<QBB4HH', ['timestamp_us', 'pedal_id', 'axis_count', 'axes*4', 'switches']),
    'eyeball_state': ('<Q4fB' + 'Bf' * 4, ['timestamp_us', 'q_wxyz*4', 'port_count'] +
                      sum([[f'port{i}_flags', f'port{i}_depth_mm'] for i in range(4)], [])),
}
SIZES = dict(heartbeat=11, device_info=13, time_sync=26, status=15, config=7, calib_request=4,
             calib_result=21, pose_sample=41, pedal_state=20, eyeball_state=45)


def payload(kind, f):
    fmt, names = LAYOUT[kind]
    vals = []
    for n in names:
        if '*' in n:
            vals += list(f[n.split('*')[0]])
        else:
            vals.append(f[n])
    p = struct.pack(fmt, *vals)
    assert len(p) == SIZES[kind], (kind, len(p))
    return p


def packet(kind, seq, f, major=MAJOR, minor=MINOR, type_override=None, extra=b''):
    p = payload(kind, f) + extra
    return bytes([(major << 4) | minor, type_override or T[kind], seq, len(p)]) + p


def serial(pkt, corrupt_at=None):
    body = pkt + struct.pack('>I', crc32c(pkt))
    if corrupt_at is not None:
        body = bytearray(body)
        body[corrupt_at] ^= 0x10
        body = bytes(body)
    return cobs(body) + b'\x00'


def usb(pkt):
    return pkt + struct.pack('>H', crc16(pkt))


def can_id(kind, node):
    return (PRIO.get(kind, 6) << 26) | (T[kind] << 18) | node


def canfd(kind, pkt, node):
    for L in (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64):
        if L >= len(pkt):
            break
    data = pkt + b'\x00' * (L - len(pkt))
    return struct.pack('>IBB', can_id(kind, node), 1, len(data)) + data


def can8(kind, pkt, node, tid):
    cid = can_id(kind, node)
    if len(pkt) <= 7:
        return struct.pack('>IBB', cid, 0, len(pkt) + 1) + pkt + bytes([0xE0 | tid])
    s = pkt + struct.pack('>H', crc16(pkt))
    out, toggle = b'', 0x20
    for off in range(0, len(s), 7):
        chunk = s[off:off + 7]
        tail = toggle | tid | (0x80 if off == 0 else 0) | (0x40 if off + 7 >= len(s) else 0)
        out += struct.pack('>IBB', cid, 0, len(chunk) + 1) + chunk + bytes([tail])
        toggle ^= 0x20
    return out


def fmtv(v):
    if isinstance(v, (list, tuple)):
        return ','.join(fmtv(x) for x in v)
    if isinstance(v, float):
        return '%.9g' % f32(v)
    return str(v)


def describe(kind, seq, f, minor=MINOR):
    s = f'{kind} seq={seq}'
    if minor != MINOR:
        s += f' version_minor={minor}'
    _, names = LAYOUT[kind]
    for n in names:
        n = n.split('*')[0]
        s += f' {n}={fmtv(f[n])}'
    return s


h = math.sqrt(0.5)
M = {
    'heartbeat': dict(uptime_us=123456789012, device_state=1, error_count=3),
    'device_info': dict(device_type=1, hw_revision=2, serial=0xA1B2C3D4, fw_major=1, fw_minor=4, fw_patch=2,
                        proto_major=1, proto_minor=0, sample_rate_hz=1000),
    'time_sync': dict(phase=1, exchange=9, host_tx_us=1700000000000000, device_rx_us=5000000, device_tx_us=5000042),
    'status': dict(severity=2, code=0x0102, detail=0xDEADBEEF, timestamp_us=42),
    'config': dict(op=1, key=1, value=500),
    'calib_request': dict(procedure=0, instrument_id=2, token=0x1234),
    'calib_result': dict(procedure=0, instrument_id=2, token=0x1234, result=0, residual_mm=0.125,
                         offset_mm=[f32(0.5), f32(-1.25), f32(30.0)]),
    'pose_sample': dict(timestamp_us=1234567, instrument_id=1, tool_type=3, tip_mm=[12.5, -3.25, 21.0],
                        q_wxyz=[f32(h), 0.0, f32(h), 0.0], actuation=32768, quality_pct=97),
    'pedal_state': dict(timestamp_us=987654, pedal_id=0, axis_count=2, axes=[65535, 1000, 0, 0], switches=0x0005),
    'eyeball_state': dict(timestamp_us=555000, q_wxyz=[1.0, 0.0, 0.0, 0.0], port_count=3,
                          port0_flags=1, port0_depth_mm=12.5, port1_flags=0, port1_depth_mm=0.0,
                          port2_flags=1, port2_depth_mm=4.0, port3_flags=0, port3_depth_mm=0.0),
}
for k in M:
    M[k] = {n: (f32(v) if isinstance(v, float) else [f32(x) if isinstance(x, float) else x for x in v]
                if isinstance(v, list) else v) for n, v in M[k].items()}

lines = ['# VP test vectors, written by gen_vectors.py from PROTOCOL.md.',
         '# <file> <transport> | <meaning>   meaning is the decoded message (vitreo::proto::describe form)',
         '#                                  or "error <STATUS>" for frames a decoder must reject.',
         '# serial: COBS frame incl. 0x00 delimiter. usb: one transfer. can files: per frame',
         '#   [CAN ID u32 big-endian][1 = FD, 0 = classic][data length][data].']


def add(name, transport, data, meaning):
    with open(name, 'wb') as fh:
        fh.write(data)
    lines.append(f'{name} {transport} | {meaning}')


seq = 0
for kind in M:
    seq += 1
    pkt = packet(kind, seq, M[kind])
    add(f'{kind}.serial.bin', 'serial', serial(pkt), describe(kind, seq, M[kind]))
    add(f'{kind}.usb.bin', 'usb', usb(pkt), describe(kind, seq, M[kind]))
    add(f'{kind}.canfd.bin', 'can', canfd(kind, pkt, 17), describe(kind, seq, M[kind]))
    add(f'{kind}.can8.bin', 'can', can8(kind, pkt, 17, seq & 31), describe(kind, seq, M[kind]))

pose = M['pose_sample']
add('newer_minor.serial.bin', 'serial', serial(packet('pose_sample', 200, pose, minor=3, extra=b'\x01\x02')),
    describe('pose_sample', 200, pose, minor=3))
add('bad_crc.serial.bin', 'serial', serial(packet('pose_sample', 201, pose), corrupt_at=20), 'error CRC')
add('major2.serial.bin', 'serial', serial(packet('pose_sample', 202, pose, major=2)), 'error VERSION')
add('unknown_type.serial.bin', 'serial', serial(packet('pose_sample', 203, pose, type_override=0x7E)),
    'error UNKNOWN_TYPE')
# 1.1's tool types: the blade and the sideways blade; the first code past them is out of range.
blade = dict(pose, tool_type=9)
add('blade_pose.serial.bin', 'serial', serial(packet('pose_sample', 208, blade)), describe('pose_sample', 208, blade))
sideways = dict(pose, tool_type=10)
add('sideways_blade_pose.usb.bin', 'usb', usb(packet('pose_sample', 209, sideways)), describe('pose_sample', 209, sideways))
add('sideways_blade_pose.canfd.bin', 'can', canfd('pose_sample', packet('pose_sample', 209, sideways), 17),
    describe('pose_sample', 209, sideways))
add('tool_type_11.usb.bin', 'usb', usb(packet('pose_sample', 210, dict(pose, tool_type=11))), 'error RANGE')
nan = dict(pose, tip_mm=[float('nan'), 0.0, 0.0])
add('nan_tip.serial.bin', 'serial', serial(packet('pose_sample', 204, nan)), 'error RANGE')
far = dict(pose, tip_mm=[f32(900.0), 0.0, 0.0])
add('far_tip.usb.bin', 'usb', usb(packet('pose_sample', 205, far)), 'error RANGE')
short = packet('pose_sample', 206, pose)
short = bytes([short[0], short[1], short[2], 40]) + short[4:44]
add('short_pose.usb.bin', 'usb', usb(short), 'error LENGTH')
add('bad_cobs.serial.bin', 'serial', b'\x05\x11\x22\x00', 'error FRAMING')
bad = bytearray(canfd('pose_sample', packet('pose_sample', 207, pose), 17))
bad[1] ^= 0x04  # CAN ID says heartbeat-ish type, packet says pose
add('id_mismatch.canfd.bin', 'can', bytes(bad), 'error FRAMING')

with open('vectors.txt', 'w') as fh:
    fh.write('\n'.join(lines) + '\n')
print(f'{len(lines) - 5} vectors')
