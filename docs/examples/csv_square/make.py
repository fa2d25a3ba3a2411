#!/usr/bin/env python3
"""Writes the example CSV directory of docs/import_formats.md: a differential-drive robot drives a
4 m square twice at 0.4 m/s and turns in place (delta_s = 0) at the corners; odometry at 20 Hz
(delta_s, delta_theta with 1% scale error and noise), range-bearing observations of 6 landmarks
at 5 Hz (every other one with id "unknown"; noise 0.1 m, 0.02 rad), range-only beacons at 2 Hz
(0.1 m), ground truth at 20 Hz,
times in seconds from 1000 s. Deterministic (seed 7)."""
import math
import random

random.seed(7)
LANDMARKS = [(1, -1.0, -1.0), (2, 5.0, -1.0), (3, 5.0, 5.0), (4, -1.0, 5.0), (5, 2.0, -1.5), (6, 2.0, 5.5)]
BEACONS = [(11, -2.0, 2.0), (12, 6.0, 2.0), (13, 2.0, 7.0)]
DT = 0.05

def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))

# motion: (speed, yaw rate, duration) segments
segs = []
for _ in range(2):
    for _ in range(4):
        segs.append((0.4, 0.0, 10.0))            # 4 m straight
        segs.append((0.0, math.pi / 2 / 3.0, 3.0))  # quarter turn in place, 3 s
x, y, th, t = 0.0, 0.0, 0.0, 1000.0
odo, truth, obs, bea = [], [(t, x, y, th)], [], []
k = 0
for v, w, dur in segs:
    for _ in range(int(round(dur / DT))):
        k += 1
        ds, dth = v * DT, w * DT
        x += ds * math.cos(th + dth / 2)
        y += ds * math.sin(th + dth / 2)
        th = wrap(th + dth)
        t += DT
        truth.append((t, x, y, th))
        odo.append((t, ds * 1.01 + random.gauss(0, 0.0005) * (ds > 0), dth * 0.99 + random.gauss(0, 0.0005)))
        if k % 4 == 0:  # 5 Hz: the nearest two landmarks
            near = sorted(LANDMARKS, key=lambda l: math.hypot(l[1] - x, l[2] - y))[:2]
            for j, (i, lx, ly) in enumerate(near):
                r = math.hypot(lx - x, ly - y) + random.gauss(0, 0.1)
                b = wrap(math.atan2(ly - y, lx - x) - th + random.gauss(0, 0.02))
                obs.append((t + 0.001, i if (k // 4 + j) % 2 else "unknown", r, b))
        if k % 10 == 0:  # 2 Hz: one beacon in turn
            i, bx, by = BEACONS[(k // 10) % 3]
            bea.append((t + 0.002, i, math.hypot(bx - x, by - y) + random.gauss(0, 0.1)))

with open("map.csv", "w") as f:
    f.write("id,x,y\n")
    for i, a, b in LANDMARKS + BEACONS:
        f.write(f"{i},{a},{b}\n")
with open("odometry.csv", "w") as f:
    f.write("time,delta_s,delta_theta\n")
    for r in odo:
        f.write("%.3f,%.6f,%.6f\n" % r)
with open("landmarks.csv", "w") as f:
    f.write("time,landmark_id,range,bearing\n")
    for r in obs:
        f.write("%.3f,%s,%.4f,%.5f\n" % r)
with open("beacons.csv", "w") as f:
    f.write("time,beacon_id,range\n")
    for r in bea:
        f.write("%.3f,%d,%.4f\n" % r)
with open("ground_truth.csv", "w") as f:
    f.write("time,x,y,heading\n")
    for r in truth:
        f.write("%.3f,%.5f,%.5f,%.6f\n" % r)
