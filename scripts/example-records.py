#!/usr/bin/env python3
"""Writes the measured-like records under examples/ that the README's commands read.

    python3 scripts/example-records.py [--host-sim target/release/host-sim]

The pole is examples/pole.toml: the paper's arm with the ball locked, 0.3 % structural damping
at its first mode and a generalized-alpha integrator (no numerical damping to speak of), so
that `identify` has a known answer (f1 = 4.147 Hz, zeta = 0.3 %). Two base acceleration records
drive it (written next to the outputs, seeded, so every run of this script writes the same
files):

- examples/tap.csv: a tap on the pole, the base up by a 0.5 mm sin^4 bump over 50 ms at
  t = 0.5 s and back, then 20 s at rest;
- examples/ambient-base.csv: 200 s of band-limited Gaussian base acceleration (white to 20 Hz,
  0.05 m/s^2 RMS), an ambient excitation.

The tip's absolute acceleration of each run (the run CSV's `tip_acceleration`), thinned to the
rate a monitor logs and with the noise of a MEMS accelerometer added (Gaussian, 2 mm/s^2 RMS;
the ADXL355's noise density 25 ug/sqrt(Hz) over a 60 Hz band), is written as

- examples/decay.csv   (t, tip_acceleration: 20 s at 200 Hz; `identify --csv examples/decay.csv`)
- examples/ambient.csv (t, tip_acceleration: 200 s at 50 Hz; `identify --record ambient`)

Standard library only; runs `host-sim run` twice (about 10 s in release).
"""

import argparse
import csv
import math
import os
import random
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLES = os.path.join(ROOT, "examples")
NOISE = 2e-3  # accelerometer noise [m/s^2 RMS]


def write_tap(path):
    """A tap: the base up by D sin^4(pi (t - 0.5) / T), D = 0.5 mm, T = 50 ms, and back (its
    acceleration, velocity and displacement start and end at zero; peak 3.9 m/s^2), sampled at
    1 ms around it and 10 ms elsewhere, 20.5 s long."""
    d, span = 0.5e-3, 0.05
    w = math.pi / span

    def accel(t):
        if not 0.5 <= t <= 0.5 + span:
            return 0.0
        s, c = math.sin(w * (t - 0.5)), math.cos(w * (t - 0.5))
        return d * w * w * (12 * s * s * c * c - 4 * s**4)

    times = sorted({round(k * 0.01, 3) for k in range(2051)}
                   | {round(0.49 + k * 1e-3, 3) for k in range(71)})
    with open(path, "w") as f:
        f.write("# base acceleration [m/s^2]: a tap, the base up by 0.5 mm sin^4 over 50 ms at "
                "t = 0.5 s and back\n")
        f.write("t,accel\n")
        for t in times:
            f.write(f"{t:.3f},{accel(t):.6g}\n")


def write_ambient_base(path, seed=30):
    """Gaussian samples every 25 ms (white to 20 Hz), linear between them, 200.1 s."""
    rng = random.Random(seed)
    with open(path, "w") as f:
        f.write("# base acceleration: band-limited Gaussian noise, 0.05 m/s^2 RMS\n")
        f.write("t,accel\n")
        for k in range(8005):
            f.write(f"{k * 0.025:.3f},{rng.gauss(0.0, 0.05):.6g}\n")


def run(host_sim, scene, record, duration, out):
    """`host-sim run` of the pole scene driven by `record`; returns the CSV rows."""
    with open(os.path.join(EXAMPLES, scene)) as f:
        text = f.read().replace('file = "tap.csv"', f'file = "{record}"')
    scene_path = os.path.join(out, "pole.toml")
    with open(scene_path, "w") as f:
        f.write(text)
    subprocess.run(
        [host_sim, "run", "--scene", scene_path, "--duration", str(duration),
         "--out", out, "--no-plots"],
        check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "pole.csv")) as f:
        lines = [line for line in f if not line.startswith("#")]
    return list(csv.DictReader(lines))


def write_record(path, rows, every, seed, comment):
    rng = random.Random(seed)
    with open(path, "w") as f:
        f.write(f"# {comment}\n")
        f.write("# tip_acceleration: absolute vertical acceleration of the arm's tip [m/s^2], "
                f"with {NOISE * 1e3:g} mm/s^2 RMS sensor noise; written by "
                "scripts/example-records.py\n")
        f.write("t,tip_acceleration\n")
        for r in rows[::every]:
            a = float(r["tip_acceleration"]) + rng.gauss(0.0, NOISE)
            f.write(f"{float(r['t']):.3f},{a:.5g}\n")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--host-sim", default=os.path.join(ROOT, "target", "release", "host-sim"))
    args = p.parse_args()
    if not os.path.exists(args.host_sim):
        sys.exit(f"{args.host_sim} not found: cargo build --release -p host-sim first")
    with tempfile.TemporaryDirectory() as tmp:
        write_tap(os.path.join(tmp, "tap.csv"))
        write_ambient_base(os.path.join(tmp, "ambient-base.csv"))
        # The tap record is shipped too: `run --scene examples/pole.toml` reads it.
        write_tap(os.path.join(EXAMPLES, "tap.csv"))
        rows = run(args.host_sim, "pole.toml", os.path.join(tmp, "tap.csv"), 20.0, tmp)
        # h = 2.5 ms: every 2nd row is 200 Hz.
        write_record(os.path.join(EXAMPLES, "decay.csv"), rows, 2, 1,
                     "free decay of examples/pole.toml after a base tap at 0.5 s "
                     "(f1 = 4.147 Hz, zeta = 0.3 %)")
        rows = run(args.host_sim, "pole.toml", os.path.join(tmp, "ambient-base.csv"), 200.0, tmp)
        write_record(os.path.join(EXAMPLES, "ambient.csv"), rows, 8, 2,
                     "ambient response of examples/pole.toml to 200 s of random base motion "
                     "(f1 = 4.147 Hz, zeta = 0.3 %)")
    for name in ("tap.csv", "decay.csv", "ambient.csv"):
        path = os.path.join(EXAMPLES, name)
        print(f"{os.path.relpath(path, ROOT)}: {os.path.getsize(path) / 1024:.0f} KiB")


if __name__ == "__main__":
    main()
