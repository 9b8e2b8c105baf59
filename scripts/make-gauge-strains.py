#!/usr/bin/env python3
"""A synthetic strain-gauge record of a detail with [[detail.gauge]] (issue 33, docs/gauges.md),
generated from a run of the model itself: the record peritwin-stream --format gauges reads.
Python 3 standard library only; with the same arguments and --seed the files are the same.

1. The truth's load cycles: blocks of --block cycles at P_max = --p-max * (1 + --spread * z)
   (z standard normal, clipped to +-2.5), R = --r, alpha = 0, --cycles in all.
2. The truth's model runs them (peritwin-replay --in-process --json on --config, which may be
   another model than the twin's, e.g. a faster-growing crack): every STATE gives the gauges'
   influence coefficients of its bond state (strain per N, constant / cos a / sin a cases).
3. Samples at each cycle's valley and peak (--rate samples per second): the strain of each gauge
   is P * (c0 + c1 cos a + c2 sin a) with the coefficients of the last state before the cycle,
   plus normal noise of the gauge's `noise` (times --noise-scale).

Writes OUT (header "time_s,<gauge ids>", then "t,strain,...") and, with --truth, the truth's
loads "time_s,load_N,angle_rad" of the same samples (for comparing identified loads).

Usage: python3 scripts/make-gauge-strains.py --config examples/b1-ct-al6061.toml \\
           --bin build/bin --out out/b1-strains.csv [--truth out/b1-truth.csv] [--seed 33]
"""
import argparse
import json
import math
import os
import random
import subprocess
import sys
import tempfile
import tomllib


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--config", required=True, help="the truth's detail config (TOML)")
    ap.add_argument("--detail", default="", help="detail id (default: the config's first)")
    ap.add_argument("--bin", default="build/bin", help="directory of peritwin-replay")
    ap.add_argument("--out", required=True, help="the strain record (CSV)")
    ap.add_argument("--truth", default="", help="also write the truth's loads here (CSV)")
    ap.add_argument("--truth-states", default="",
                    help="also write the truth's cycles,crack_length_m per state here (CSV)")
    ap.add_argument("--cycles", type=int, default=40000)
    ap.add_argument("--block", type=int, default=100, help="cycles per load level")
    ap.add_argument("--p-max", type=float, default=4000.0, help="mean P_max (N)")
    ap.add_argument("--spread", type=float, default=0.05, help="relative std of P_max")
    ap.add_argument("--r", type=float, default=0.1, help="load ratio")
    ap.add_argument("--rate", type=float, default=20.0, help="samples per second")
    ap.add_argument("--noise-scale", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=33)
    a = ap.parse_args()

    with open(a.config, "rb") as f:
        config = tomllib.load(f)
    details = config["detail"]
    detail = next((d for d in details if d["id"] == a.detail), details[0]) if a.detail else details[0]
    gauges = detail.get("gauge", [])
    if not gauges:
        sys.exit(f"{a.config}: detail {detail['id']} has no [[detail.gauge]]")
    rng = random.Random(a.seed)

    # 1. The truth's cycles, block by block.
    blocks = []
    left = a.cycles
    while left > 0:
        n = min(a.block, left)
        z = max(-2.5, min(2.5, rng.gauss(0.0, 1.0)))
        blocks.append((round(a.p_max * (1 + a.spread * z), 1), n))
        left -= n

    # 2. The truth's model over them: the gauges' coefficients after every batch. Its config
    # without what only a live twin needs (a learning ensemble, remaining-life estimates).
    with tempfile.TemporaryDirectory() as tmp:
        truth_config = os.path.join(tmp, "truth.toml")
        with open(a.config) as f, open(truth_config, "w") as t:
            table = ""
            for line in f:
                stripped = line.strip()
                if stripped.startswith("["):
                    table = stripped
                if table == "[detail.uncertainty]":
                    continue
                if table == "[detail.life]" and stripped.startswith("every_batches"):
                    line = "every_batches = 0\n"
                t.write(line)
        history = os.path.join(tmp, "cycles.csv")
        with open(history, "w") as h:
            h.write("p_max_N,r,angle_rad,count\n")
            for p, n in blocks:
                h.write(f"{p},{a.r},0,{n}\n")
        run = subprocess.run(
            [os.path.join(a.bin, "peritwin-replay"), "--config", truth_config, "--history", history,
             "--in-process", "--json", "--batch-cycles", str(a.block)]
            + (["--detail", a.detail] if a.detail else []),
            capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit("peritwin-replay failed:\n" + run.stderr)
    states = []  # (cycles, {id: (c0, c1, c2)})
    cracks = []  # (cycles, crack length)
    for line in run.stdout.splitlines():
        s = json.loads(line)
        if "gauges" in s and "state_seq" in s:
            states.append((s["cycles"], {k: v["per_n"] for k, v in s["gauges"].items()}))
            cracks.append((s["cycles"], s["crack_length_m"]))
    if a.truth_states:
        with open(a.truth_states, "w") as f:
            f.write("cycles,crack_length_m\n")
            for c, length in cracks:
                f.write(f"{c},{length}\n")
    if not states:
        sys.exit("peritwin-replay printed no state with gauges")
    ended = states[-1][0]

    # 3. Samples at each cycle's valley and peak, with each gauge's noise.
    ids = [g["id"] for g in gauges]
    noise = [a.noise_scale * g.get("noise", 0.0) for g in gauges]
    dt = 1.0 / a.rate
    t = 0.0
    cycle = 0
    k = 0  # the state in force: the last with cycles <= cycle
    with open(a.out, "w") as out, (open(a.truth, "w") if a.truth else open(os.devnull, "w")) as truth:
        out.write("# " + f"synthetic strain record of {detail['id']} (scripts/make-gauge-strains.py "
                  f"--seed {a.seed}, {a.cycles} cycles, noise x{a.noise_scale})\n")
        out.write("time_s," + ",".join(ids) + "\n")
        truth.write("time_s,load_N,angle_rad\n")
        for p_max, n in blocks:
            for _ in range(n):
                if cycle >= ended:
                    break
                while k + 1 < len(states) and states[k + 1][0] <= cycle:
                    k += 1
                c = states[k][1]
                for p in (a.r * p_max, p_max):
                    strains = []
                    for g, gid in enumerate(ids):
                        c0, c1, _ = (v if v is not None else 0.0 for v in c[gid])
                        e = p * (c0 + c1)  # alpha = 0: cos 0 = 1, sin 0 = 0
                        strains.append(e + (rng.gauss(0.0, noise[g]) if noise[g] > 0 else 0.0))
                    out.write(f"{t:.3f}," + ",".join(f"{e:.6e}" for e in strains) + "\n")
                    truth.write(f"{t:.3f},{p:.1f},0\n")
                    t += dt
                cycle += 1
    print(f"{a.out}: {cycle} cycles ({2 * cycle} samples, {len(ids)} gauges); the truth's model "
          f"ended at {ended} cycles, {len(states)} states", file=sys.stderr)


if __name__ == "__main__":
    main()
