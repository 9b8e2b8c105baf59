#!/usr/bin/env python3
"""Writes examples/b1-gauge.csv: a synthetic strain-gauge record of the B1 compact-tension detail
for peritwin-stream (README, "Streaming from sensors"). Python 3 standard library only; the seed
is fixed, so the file is the same on every run.

The record: about 40 000 load cycles at around the demo's level (P_max 4 kN, R 0.1), sampled at
the peaks and valleys (10 Hz cycles, 20 samples per second) with
  * variable amplitude: P_max drifts slowly by +-8 % (two sines of 3000 and 710 cycles),
  * noise: +-1.5 % of P_max on every sample (uniform), rounded to the gauge's 1 N resolution,
  * small vibration cycles: every 25th cycle has an extra wiggle on its way up (a few % of P_max),
  * a few overloads: 6 single cycles at 5.2 kN (1.3 x), which the rainflow counting keeps.
Columns: the series format (time_s,load_N), loads already in N (the example config has no
[detail.sensor] table: scale 1, offset 0).

Usage: python3 scripts/make-gauge-series.py [OUT]   (default examples/b1-gauge.csv)
"""
import math
import random
import sys

CYCLES = 40_000
P_MAX = 4000.0
R = 0.1
RATE_HZ = 20.0  # two samples per 10 Hz cycle (plus the wiggles' extra samples)
OVERLOAD_AT = {3_000, 9_500, 17_000, 24_000, 31_500, 37_000}
OVERLOAD = 1.3


def main() -> None:
    out_path = sys.argv[1] if len(sys.argv) > 1 else "examples/b1-gauge.csv"
    rng = random.Random(20261203)
    lines = [
        "# B1 strain-gauge record (synthetic, scripts/make-gauge-series.py, seed 20261203):",
        "# ~40 000 cycles at P_max ~4 kN, R 0.1, +-8 % drift, +-1.5 % noise, vibration wiggles,",
        "# 6 overloads at 5.2 kN. Peaks and valleys at 20 samples/s; loads in N.",
        "time_s,load_N",
    ]
    t = 0.0
    dt = 1.0 / RATE_HZ
    for n in range(CYCLES):
        drift = 1.0 + 0.05 * math.sin(2 * math.pi * n / 3000.0) + 0.03 * math.sin(
            2 * math.pi * n / 710.0)
        p_max = P_MAX * drift * (OVERLOAD if n in OVERLOAD_AT else 1.0)
        p_min = R * P_MAX * drift

        def noisy(p: float) -> float:
            return round(p + rng.uniform(-0.015, 0.015) * P_MAX)

        lines.append(f"{t:.3f},{noisy(p_min)}")
        t += dt
        if n % 25 == 0:  # a vibration wiggle on the way up: a small extra cycle
            mid = 0.5 * (p_min + p_max)
            lines.append(f"{t - dt / 2:.3f},{noisy(mid + 0.04 * P_MAX)}")
            lines.append(f"{t - dt / 4:.3f},{noisy(mid - 0.04 * P_MAX)}")
        lines.append(f"{t:.3f},{noisy(p_max)}")
        t += dt
    lines.append(f"{t:.3f},{round(R * P_MAX)}")
    with open(out_path, "w", encoding="ascii", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
