"""An LCM log read from its specification (lcm-logger's format: per event a big-endian sync word
0xEDA1DA01, event number, timestamp, channel and data lengths, then the channel and the data), not
through LCM's or vitreo's reader: the report tests' independent view of what the rig published."""
import struct


def read_log(path):
    """[(channel, data bytes)] of every event; asserts the file ends on an event boundary."""
    with open(path, "rb") as f:
        data = f.read()
    at, out = 0, []
    while at + 28 <= len(data):
        sync, num, utime, clen, dlen = struct.unpack(">IqqII", data[at:at + 28])
        assert sync == 0xEDA1DA01, f"no sync word at {at}"
        chan = data[at + 28:at + 28 + clen].decode()
        body = data[at + 28 + clen:at + 28 + clen + dlen]
        out.append((chan, body))
        at += 28 + clen + dlen
    assert at == len(data), "the log does not end on an event boundary"
    return out
