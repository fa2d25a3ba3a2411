#!/usr/bin/env python3
"""Writes the seed corpus of the fuzz targets (corpus/<target>/seed_*) and their dictionaries
(<target>.dict) from the repository's test data, configs and lcmtypes. Deterministic: running it
again gives the same files. Inputs found by fuzzing (crash-*, regression_*) are left alone.

Usage: tests/fuzz/make_corpus.py  (from anywhere; needs lcm-gen, liblcm-bin)."""
import glob
import os
import random
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SHARED = os.path.join(ROOT, "..", "shared", "data")
SYNC = 0xEDA1DA01
# fuzz_lcm_input.cpp's channel index: kSensorInputs' channels in order, then FUSION_CONTROL.
CHANNELS = ["ODOMETRY", "MAGRULER", "MAGRULER_FAULT", "IMU", "GPS", "LANDMARKS", "BEACONS", "VISION",
            "FUSION_CONTROL"]
# fuzz_lcm_input.cpp's configs.
PAPER, GPS_PAPER, INS_VISION, LANDMARK = 0, 1, 2, 3


def lcm_types():
    out = tempfile.mkdtemp()
    subprocess.run(["lcm-gen", "-p", "--ppath", out] + sorted(glob.glob(os.path.join(ROOT, "lcmtypes", "*.lcm"))),
                   check=True, stdout=subprocess.DEVNULL)
    sys.path.insert(0, out)
    import lcmloc  # noqa: E402  (generated just now)
    return lcmloc


def read_log(path):
    """(channel, utime, payload) of each event of an intact log."""
    data = open(path, "rb").read()
    pos, events = 0, []
    while pos + 28 <= len(data):
        sync, _, utime, clen, dlen = struct.unpack(">IqqII", data[pos:pos + 28])
        assert sync == SYNC, path
        ch = data[pos + 28:pos + 28 + clen].decode()
        events.append((ch, utime, data[pos + 28 + clen:pos + 28 + clen + dlen]))
        pos += 28 + clen + dlen
    return events


def log_bytes(events):
    out = bytearray()
    for n, (ch, utime, payload) in enumerate(events):
        c = ch.encode()
        out += struct.pack(">IqqII", SYNC, n, utime, len(c), len(payload)) + c + payload
    return bytes(out)


def input_seed(config, events):
    out = bytearray([config])
    for ch, _, payload in events:
        out += bytes([CHANNELS.index(ch)]) + struct.pack(">H", len(payload)) + payload
    return bytes(out)


def write(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed_" + name), "wb") as f:
        f.write(data)


def first(events, per_channel):
    """The first per_channel events of each input channel, in log order."""
    seen, out = {}, []
    for e in events:
        if e[0] in CHANNELS and seen.get(e[0], 0) < per_channel:
            seen[e[0]] = seen.get(e[0], 0) + 1
            out.append(e)
    return out


def made_messages(t):
    """One message of each input type that the golden logs lack, and each control command."""
    msgs = []
    lo = t.landmark_obs_t()
    lo.utime, lo.seq, lo.landmark_id, lo.range, lo.bearing, lo.range_std, lo.bearing_std = 1000, 0, 3, 12.5, 0.4, 0.1, 0.02
    msgs.append(("LANDMARKS", lo))
    br = t.beacon_range_t()
    br.utime, br.seq, br.beacon_id, br.range, br.range_std = 2000, 0, 1, 8.0, 0.05
    msgs.append(("BEACONS", br))
    lb = t.landmark_bearings_t()
    lb.utime, lb.seq, lb.count, lb.landmark_ids, lb.bearings, lb.bearing_std = 3000, 0, 3, [1, 2, 3], [0.1, 1.2, -2.0], 0.01
    msgs.append(("VISION", lb))
    for cmd, filt, params in [(1, "ekf", ""), (1, "", "{type: ukf, p0_diag: [0.01, 0.01, 0.001]}"), (2, "", ""), (3, "", "")]:
        c = t.fusion_control_t()
        c.utime, c.seq, c.command, c.filter, c.parameters = 4000 + cmd, cmd, cmd, filt, params
        c.pose, c.pose_std = [1.0, 2.0, 0.5], [0.1, 0.1, 0.05]
        msgs.append(("FUSION_CONTROL", c))
    return [(ch, m.utime, m.encode()) for ch, m in msgs]


def lcm_input(t):
    golden = os.path.join(ROOT, "tests", "data", "golden")
    ruler, gps, ins = (read_log(os.path.join(golden, n + ".lcmlog")) for n in ("ruler", "gps", "ins"))
    for name, config, events in (("ruler", PAPER, ruler), ("gps", GPS_PAPER, gps), ("ins_vision", INS_VISION, ins)):
        write("lcm_input", name, input_seed(config, first(events, 20)))
        # A stretch of the log around the first message of each channel but the odometry and
        # the IMU (in one stretch of time, as the daemon gets them).
        for ch in sorted({e[0] for e in events} - {"ODOMETRY", "IMU"}):
            i = next(k for k, e in enumerate(events) if e[0] == ch)
            write("lcm_input", "%s_%s" % (name, ch.lower()), input_seed(config, events[max(0, i - 30):i + 4]))
    made = made_messages(t)
    odo = [e for e in ruler if e[0] == "ODOMETRY"][:10]
    write("lcm_input", "landmarks", input_seed(LANDMARK, odo[:5] + made[:2] + odo[5:]))
    write("lcm_input", "control", input_seed(PAPER, odo[:5] + made[3:] + odo[5:]))
    write("lcm_input", "vision", input_seed(INS_VISION, made[2:3]))
    # The same through the intake only (fuzz_lcm_input.cpp: byte 0's high bit).
    d = os.path.join(HERE, "corpus", "lcm_input")
    for name in sorted(os.listdir(d)):
        if name.startswith("seed_") and not name.startswith("seed_intake_"):
            data = open(os.path.join(d, name), "rb").read()
            write("lcm_input", "intake_" + name[len("seed_"):], bytes([data[0] | 0x80]) + data[1:])
    # The dictionary: every type's fingerprint (the first 8 bytes of its messages).
    with open(os.path.join(HERE, "lcm_input.dict"), "w") as f:
        f.write("# The fingerprints of the lcmloc types (make_corpus.py).\n")
        for name in sorted(n for n in dir(t) if n.endswith("_t")):
            fp = getattr(t, name)._get_packed_fingerprint()
            f.write('%s="%s"\n' % (name, "".join("\\x%02x" % b for b in fp)))
    return ruler, gps, ins, made


def log_seeds(ruler, gps, ins, made):
    rng = random.Random(37)
    small = log_bytes(first(ruler, 8))
    write("log", "ruler", small)
    write("log", "gps", log_bytes(first(gps, 6)))
    write("log", "ins_vision", log_bytes(first(ins, 6)))
    write("log", "made", log_bytes(made))
    write("log", "cut_mid_event", small[: len(small) - 17])
    flipped = bytearray(small)
    flipped[len(flipped) // 2] ^= 0x5A
    write("log", "flipped_byte", bytes(flipped))
    garbage = bytes(rng.randrange(256) for _ in range(64))
    write("log", "garbage_between", small[:len(small) // 2] + garbage + small)
    write("log", "not_a_log", b"time,x,y\n0,1,2\n")
    with open(os.path.join(HERE, "log.dict"), "w") as f:
        f.write('# LCM log syntax (make_corpus.py).\nsync="\\xed\\xa1\\xda\\x01"\n')
        for ch in CHANNELS + ["POSE", "POSE_EKF", "GATE", "GROUND_TRUTH", "FAULT_EVENTS", "FUSION_STATUS"]:
            f.write('"%s"\n' % ch)


def config_seeds():
    for path in sorted(glob.glob(os.path.join(ROOT, "config", "*.yaml"))):
        text = open(path, "rb").read()
        if len(text) > 16384:
            continue
        if b"\nprocesses:" in text:  # a launcher's system file, its scenario next to it
            lines = text.split(b"\n")
            scenario = [ln.split(b":", 1)[1].split(b"#")[0].strip() for ln in lines if ln.startswith(b"scenario:")][0]
            launch = b"\n".join(b"scenario: scenario.yaml" if ln.startswith(b"scenario:") else ln for ln in lines)
            write("config", "launch_" + os.path.basename(path), b"\x04" + launch + b"\x00" +
                  open(os.path.join(ROOT, "config", scenario.decode()), "rb").read())
        else:  # a map file it names goes after the NUL byte, as map.csv
            maps = [ln.split(b":", 1)[1].split(b"#")[0].strip() for ln in text.split(b"\n")
                    if ln.strip().startswith(b"map_file:")]
            if maps:
                text = text.replace(maps[0], b"map.csv") + b"\x00" + b"".join(
                    open(os.path.join(ROOT, "config", maps[0].decode()), "rb").readlines()[:400])
            write("config", "sim_" + os.path.basename(path), b"\x00" + text)
    paper_map = b"".join(open(os.path.join(ROOT, "config", "paper_map.csv"), "rb").readlines()[:40])
    write("config", "system_with_map", b"\x01fusion:\n  map_file: map.csv\n  filter: {type: ukf_landmarks}\n\x00" + paper_map)
    write("config", "system_landmark", b"\x01" + open(os.path.join(ROOT, "config", "landmark_paper.yaml"), "rb").read())
    write("config", "params", b"\x02{type: ukf_gated, wheelbase: 2.5, p0_diag: [0.01, 0.01, 0.001], initial_pose: [1, 2, 0.5]}")
    write("config", "params_ins", b"\x02{type: odo_ins, ins: {latitude: 47.2}}")
    write("config", "map", b"\x03" + paper_map)
    write("config", "map_bom", b"\x03\xef\xbb\xbfid,x,y\r\n1,0,0\r\n2,1e3,-4.5\r\n")
    keys = set()
    for path in glob.glob(os.path.join(ROOT, "config", "*.yaml")):
        for line in open(path):
            k = line.strip().split(":")[0].lstrip("- {")
            if k and k.replace("_", "").isalnum() and len(k) < 30:
                keys.add(k)
    with open(os.path.join(HERE, "config.dict"), "w") as f:
        f.write("# Keys of the shipped configs (make_corpus.py).\n")
        for k in sorted(keys):
            f.write('"%s:"\n' % k)


IMPORT_FILES = {
    "odo_delta": "time,delta_s,delta_theta\n0.00,0,0\n0.01,0.1,0.001\n0.02,0.1,0.002\n0.03,0.1,0\n",
    "odo_yaw_rate": "time_s,speed,yaw_rate\n0,1.0,0.1\n0.1,1.0,0.1\n0.2,1.1,0\n",
    "odo_steering": "time_us,speed,steering\n0,2.0,0.05\n100000,2.0,0.05\n200000,2.0,-0.1\n",
    "landmarks": "time,landmark_id,range,bearing,range_std,bearing_std\n0.05,1,5.0,0.3,0.1,0.01\n0.15,unknown,7,-1.2,0.1,0.02\n",
    "beacons": "time,beacon_id,range,range_std\n0.05,2,4.0,0.05\n0.1,1,3.5,0.05\n",
    "gps_local": "time,x,y,position_std\n0.1,0.1,0.0,2.0\n0.2,0.2,0.01,2.0\n",
    "gps_geo": "time,latitude,longitude\n0.1,-33.883,151.195\n0.2,-33.88301,151.19501\n",
    "truth": "time,x,y,heading\n0,0,0,0\n0.1,0.1,0,0.01\n0.2,0.2,0.001,0.02\n",
    "truth_position": "time,truth_x,truth_y\n0,0,0\n0.1,0.5,0\n0.2,1.5,0.1\n",
    "imu": "time,accel_x,accel_y,accel_z,gyro_x,gyro_y,gyro_z,mag_x,mag_y,mag_z\n0,0.1,0,9.81,0,0,0.01,0.2,0,0.4\n0.01,0.1,0,9.81,0,0,0.01,0.2,0,0.4\n",
    "map": "id,x,y\n1,10,0\n2,0,10\n3,-10,0\n",
}


def import_seeds():
    f = IMPORT_FILES
    for kind, text in f.items():
        write("import", "csv_" + kind, b"\x00" + text.encode())
    write("import", "csv_odo_landmarks_map", b"\x00" + b"\x00".join(
        f[k].encode() for k in ("odo_delta", "landmarks", "map", "truth")))
    write("import", "csv_odo_beacons_map", b"\x00" + b"\x00".join(f[k].encode() for k in ("odo_yaw_rate", "beacons", "map")))
    write("import", "csv_bom_crlf", b"\x00\xef\xbb\xbf" + f["odo_delta"].replace("\n", "\r\n").encode())

    def head(path, n):
        return b"".join(open(path, "rb").readlines()[:n]) if os.path.exists(path) else b""
    mr = os.path.join(SHARED, "mrclam_ds6")
    write("import", "mrclam", b"\x01" + b"\x00".join(head(os.path.join(mr, n), k) for n, k in (
        ("Robot1_Odometry.dat", 20), ("Robot1_Measurement.dat", 20), ("Robot1_Groundtruth.dat", 20),
        ("Landmark_Groundtruth.dat", 30), ("Barcodes.dat", 40))))
    uwb = os.path.join(SHARED, "uwb_indoor")
    write("import", "uwb", b"\x02" + b"\x00".join(head(os.path.join(uwb, n), 40) for n in (
        "Indoor_UWB_Input.txt", "Indoor_UWB_GT.txt")))
    names = set()
    for text in f.values():
        names.update(text.split("\n")[0].split(","))
    with open(os.path.join(HERE, "import.dict"), "w") as d:
        d.write("# Column names of the import formats (make_corpus.py).\n")
        for n in sorted(names) + ["unknown", "nan", "inf", "-0", "1e308"]:
            d.write('"%s"\n' % n)


def udpm_datagram(sender, datagram):
    return struct.pack(">BH", sender, len(datagram)) + datagram


def udpm_short(seqno, channel, payload):
    return struct.pack(">II", 0x4C433032, seqno) + channel + b"\0" + payload


def udpm_fragments(seqno, channel, payload, fragment):
    """LCM 1.3.1's fragments of one message: fragment 0 carries the channel, then payload bytes."""
    first = fragment - len(channel) - 1
    pieces = [payload[:first]] + [payload[i:i + fragment] for i in range(first, len(payload), fragment)]
    out, offset = [], 0
    for no, piece in enumerate(pieces):
        head = struct.pack(">IIIIHH", 0x4C433033, seqno, len(payload), offset, no, len(pieces))
        out.append(head + (channel + b"\0" if no == 0 else b"") + piece)
        offset += len(piece)
    return out


def udpm_seeds():
    payload = bytes(range(256)) * 3
    frags = udpm_fragments(7, b"FUSION_STATUS", payload, 200)
    write("udpm", "short", b"".join(udpm_datagram(1, udpm_short(k, b"ODOMETRY", bytes([k] * 57))) for k in range(3)))
    write("udpm", "fragments", b"".join(udpm_datagram(2, d) for d in frags))
    write("udpm", "fragments_reordered_duplicate",
          b"".join(udpm_datagram(2, d) for d in [frags[0], frags[2], frags[1], frags[1]] + frags[3:]))
    other = udpm_fragments(9, b"POSE", payload[:300], 120)
    write("udpm", "fragments_two_senders", b"".join(
        udpm_datagram(s, d) for pair in zip(frags, other) for s, d in zip((2, 3), pair)))
    write("udpm", "unsubscribed", b"".join(udpm_datagram(4, d) for d in udpm_fragments(1, b"XIMAGE", payload, 300)))
    write("udpm", "first_fragment_missing", b"".join(udpm_datagram(5, d) for d in frags[1:]))


def main():
    udpm_seeds()
    t = lcm_types()
    ruler, gps, ins, made = lcm_input(t)
    log_seeds(ruler, gps, ins, made)
    config_seeds()
    import_seeds()


if __name__ == "__main__":
    main()
