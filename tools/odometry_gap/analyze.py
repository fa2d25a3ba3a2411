#!/usr/bin/env python3
"""Error and sigma of a replay's POSE around an odometry gap, against GROUND_TRUTH.

usage: analyze.py TRUTH.csv POSE.csv GATE.csv GAP_START_S GAP_LENGTH_S
(CSV files of `lcmloc-log to-csv`; times relative to the first GROUND_TRUTH sample.)
Prints one JSON object: at the first pose after the gap error [m], sigma [m] (larger axis of the
position covariance), error/sigma, status; over the rest of the run the largest error/sigma, the
final error; GATE decisions of the active filter after the gap (accepted, rejected).
"""
import bisect
import csv
import json
import math
import sys


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def main():
    truth_csv, pose_csv, gate_csv, start, length = sys.argv[1:6]
    truth = [(int(r["utime"]), float(r["x"]), float(r["y"])) for r in rows(truth_csv)]
    tt = [t[0] for t in truth]
    t0 = tt[0]
    gap_end = t0 + int((float(start) + float(length)) * 1e6)

    def truth_at(u):
        i = min(max(bisect.bisect_left(tt, u), 1), len(tt) - 1)
        (ua, xa, ya), (ub, xb, yb) = truth[i - 1], truth[i]
        w = 0.0 if ub == ua else (u - ua) / (ub - ua)
        return xa + w * (xb - xa), ya + w * (yb - ya)

    out = {}
    worst = 0.0
    final = None
    for r in rows(pose_csv):
        u = int(r["utime"])
        if u < gap_end:
            continue
        x, y = float(r["state_0"]), float(r["state_1"])
        a, b, d = float(r["covariance_0_0"]), float(r["covariance_0_1"]), float(r["covariance_1_1"])
        sigma = math.sqrt(0.5 * (a + d) + math.sqrt(0.25 * (a - d) ** 2 + b * b))
        tx, ty = truth_at(u)
        err = math.hypot(x - tx, y - ty)
        if not out:
            out = {"t_after_gap_s": (u - gap_end) / 1e6, "error_m": err, "sigma_m": sigma,
                   "error_over_sigma": err / sigma, "status": int(r["status"])}
        worst = max(worst, err / sigma)
        final = err
    out["max_error_over_sigma_after"] = worst
    out["final_error_m"] = final
    acc = rej = 0
    reasons = {}
    for r in rows(gate_csv):
        if int(r["utime"]) < gap_end or r["filter"] != "ukf_gated":
            continue
        acc += r["accepted"] == "1"
        rej += r["accepted"] != "1"
        reasons[r["reason"]] = reasons.get(r["reason"], 0) + 1
    out["gate_after_gap"] = {"accepted": acc, "rejected": rej, "reasons": reasons}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
