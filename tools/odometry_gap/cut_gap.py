#!/usr/bin/env python3
"""Removes the messages of some channels whose message time (the utime, the first field of every
lcmloc type) falls in [start, start + length) seconds after the first ODOMETRY message: odometry
lost in transit, as after a SIGSTOP of the fusion daemon. Plain LCM log format, no LCM needed.

usage: cut_gap.py IN.lcmlog OUT.lcmlog START_S LENGTH_S [CHANNEL_REGEX]
       (default regex: ^(ODOMETRY|MAGRULER.*)$)
"""
import re
import struct
import sys

SYNC = 0xEDA1DA01


def events(path):
    with open(path, "rb") as f:
        data = f.read()
    pos = 0
    while pos + 28 <= len(data):
        sync, num, ts, clen, dlen = struct.unpack(">IqqII", data[pos:pos + 28])
        if sync != SYNC:
            raise SystemExit(f"{path}: bad sync word at byte {pos}")
        channel = data[pos + 28:pos + 28 + clen].decode()
        payload = data[pos + 28 + clen:pos + 28 + clen + dlen]
        yield num, ts, channel, payload
        pos += 28 + clen + dlen


def main():
    if len(sys.argv) < 5:
        raise SystemExit(__doc__)
    src, dst, start, length = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
    pattern = re.compile(sys.argv[5] if len(sys.argv) > 5 else r"^(ODOMETRY|MAGRULER.*)$")
    evs = list(events(src))
    t0 = min(struct.unpack(">q", p[8:16])[0] for _, _, c, p in evs if c == "ODOMETRY")
    lo, hi = t0 + int(start * 1e6), t0 + int((start + length) * 1e6)
    dropped = 0
    with open(dst, "wb") as out:
        n = 0
        for _, ts, channel, payload in evs:
            if pattern.match(channel) and len(payload) >= 16:
                utime = struct.unpack(">q", payload[8:16])[0]
                if lo <= utime < hi:
                    dropped += 1
                    continue
            c = channel.encode()
            out.write(struct.pack(">IqqII", SYNC, n, ts, len(c), len(payload)) + c + payload)
            n += 1
    print(f"dropped {dropped} messages with utime in [{lo}, {hi})")


if __name__ == "__main__":
    main()
